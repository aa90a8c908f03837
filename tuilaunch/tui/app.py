"""The Textual app: lays out the panels and wires them to the engine.

The app keeps the session's link (session_link.py), its one session view
(session_view.py: the session's port, tree, pane, commands and keyboard, as a fleet view
holds one per session) and the screens; each concern of its keys is an object it holds:
`keyboard` (the view's: typing into a node, tools, the command line), `inspector` (the
session's readings, plots, log levels, recordings), `navigation` (tabs and focus),
`leaving` (quit, detach, SIGTERM, SIGHUP), `status` (the status line), `starting` (the
session's server, `tuilaunch FILE`). A key
names the object and its verb (`keyboard('type_into')`). The tabs are widgets that own
their state, the app their host: the Nodes tab (nodes/tab.py's NodesTab: the tree, the
detail line and the pane, sent the session's events as messages) and the Args tab
(arguments.py's ArgsTab), as the graph tabs in screens/.
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from textual import events, on
from textual.app import ComposeResult, SystemCommand
from textual.binding import Binding
from textual.screen import Screen
from textual.widgets import Static, TabbedContent, TabPane

from ..client.port import LaunchPort
from ..client.remote_supervisor import LINK_INTERVAL, RemoteSupervisor
from ..client.served_session import ServedSession
from ..client.session_start import spawn_session
from ..engine.errors import LaunchError
from ..engine.plan.machines import Placement
from ..engine.plan.session import Session
from ..engine.run.engine_thread import EngineThread
from ..engine.run.vocabulary.lifecycle import available_transitions
from ..engine.run.vocabulary.requests import Apply, Restart, Start, Stop, Transition
from ..engine.run.vocabulary.ros_requests import LogLevel
from .arguments import ArgsTab
from .inspect.inspector import INSPECTOR_BINDINGS, Inspector
from .key_order import KeyOrder
from .keys.keyboard import KEYBOARD_BINDINGS, NodeKeyboard
from .navigation import Navigation
from .nodes.tab import NodesTab
from .quitting import LEAVING_BINDINGS, QUIT_BINDINGS, Quitting
from .screens.output_panel import OutputPanel
from .screens.tree_panel import LaunchTree, ascii_terminal
from .server_start import ServerStarted
from .session_link import DRAIN_HZ, PANE_CHROME, SessionLink
from .session_view import COMMAND_BINDINGS, SessionView, lifecycle_bindings, pane_save_dir
from .status_line import StatusLine
from .tab_panels import TabPanels
from .textual_compat import Footer

if TYPE_CHECKING:
    from .screens.topics_panel import TopicsPanel

READ_ONLY_REFUSES = frozenset({("command", "stop"), ("command", "restart"),
                               ("command", "start"), ("command", "lifecycle"), ("apply", ""),
                               ("inspector", "log_level")})
"""The app's keys whose every request a read-only client refuses: its footer hides them."""

READ_ONLY_BINDINGS = [
    Binding(key, f"keyboard('refused', {request.changes!r})", show=False)
    for key, request in (("s", Stop), ("r", Restart), ("t", Start),
                         ("right_square_bracket", Transition),
                         ("left_square_bracket", Transition), ("f5", Apply), ("L", LogLevel))]
"""The same keys in a read-only view, hidden: each says its refusal in one line (the footer
offers none of them, but a key typed out of habit is answered, not silently dropped)."""


class LaunchTabs(TabbedContent):
    """Tabs that change only when asked (keys 1-5, a click on a tab).

    TabbedContent also switches to whichever pane a widget was focused in, when its
    message arrives: with keys that arrive together (escape, 3) that message is late and
    flips the tab back."""

    def _on_tab_pane_focused(self, event: TabPane.Focused) -> None:
        event.stop()


class TuiLaunchApp(SessionLink, KeyOrder):
    """The launcher's UI: the panels laid out, wired to the engine on mount. What each
    concern does lives in an object it holds (`keyboard`, `inspector`, `navigation`,
    `leaving`) or its tab's widget (nodes, arguments); its keys name the object and the
    verb (`keyboard('type_into')`), handed over by `action_keyboard` and the like;
    key_order hands the keys out one after the other."""

    CSS_PATH = "screens/app.tcss"
    TITLE = "tuilaunch"
    first_tab = "nodes"
    """The tab shown once the session is followed (`attach --tab`)."""
    first_typing: str | None = None
    """The process typed into once the session is followed (`attach --type`, a fleet's
    `i`), as `i` on its row."""

    BINDINGS = [
        *KEYBOARD_BINDINGS,
        Binding("1", "navigation('tab', 'nodes')", "Nodes",
                tooltip="The group tree and node output"),
        Binding("2", "navigation('tab', 'args')", "Args", tooltip="Edit launch arguments"),
        Binding("3", "navigation('tab', 'services')", "Services", tooltip="Call a service"),
        Binding("4", "navigation('tab', 'params')", "Params",
                tooltip="Get and set parameters"),
        Binding("5", "navigation('tab', 'topics')", "Topics", show=False,
                tooltip="Topics, rates, QoS problems, echo"),
        *COMMAND_BINDINGS,
        Binding("a", "command('all_output')", "All", show=False, tooltip="Output of all nodes"),
        *lifecycle_bindings(),
        Binding("f5", "apply", "Apply", tooltip="Relaunch with the edited arguments"),
        *INSPECTOR_BINDINGS,
        *LEAVING_BINDINGS,
        # named here, ctrl+p too: Textual adds its own only when no binding opens the palette
        Binding("ctrl+p", "command_palette", "palette", show=False, priority=True,
                tooltip="Open the command palette"),
        Binding("colon", "command_palette", "Commands", show=False,
                tooltip="The command palette, as ctrl+p (as in vim, k9s)"),
        Binding("question_mark", "navigation('help')", "Help"),
        Binding("f1", "navigation('help')", "Help", show=False, tooltip="The keys"),
        Binding("slash", "navigation('find')", "Filter", show=False,
                tooltip="Services, Params: into the list's filter field"),
        *QUIT_BINDINGS,
        *READ_ONLY_BINDINGS,  # after the keys they stand for: only where those are off
    ]

    keyboard: NodeKeyboard
    view: SessionView
    inspector: Inspector
    status: StatusLine

    def __init__(self, *args: Any, **options: Any) -> None:
        super().__init__(*args, **options)
        save_dir = pane_save_dir(self.log_dir, self.session_host, self.session_name)
        self.view = SessionView(
            "", self.session_host, self.session_name, LaunchTree(id="tree"),
            OutputPanel(self.store, save_dir, max_lines=self.scrollback,
                        max_fps=self.pane_fps, id="output"), self.store, self, self.session)
        self.buffer, self.asked_to_stop = self.view.buffer, self.view.asked_to_stop
        self.keyboard = self.view.keyboard  # the session's (its view the keyboard's host)
        self.inspector = Inspector(self, lambda tab: self.navigation.tab(tab))
        # the Services, Params and Topics panels: made the first time their tab shows
        panels = TabPanels(self, lambda: self.inspector.graph, self.inspector.inspect)
        self.navigation = Navigation(self, self.inspector.tab_shown, panels)
        self.leaving = Quitting(self)
        self.status = StatusLine(self)

    # --- layout ----------------------------------------------------------------------

    def compose(self) -> ComposeResult:
        yield Static("", id="status")
        with LaunchTabs(initial="nodes"):
            with TabPane("1 Nodes", id="nodes"):
                yield NodesTab(self.view, self.drain, id="nodes-tab")
            with TabPane("2 Args", id="args"):
                yield ArgsTab(self.view, id="args-tab")
            # empty until first shown: most sessions never open them (tab_panels.py)
            yield TabPane("3 Services", id="services")
            yield TabPane("4 Params", id="params")
            yield TabPane("5 Topics", id="topics")
        yield Footer()

    def on_mount(self) -> None:
        # held, not queried: App.query_one searches the active screen, which is a modal
        # (help, quit) while the engine keeps reporting
        self.nodes = self.query_one(NodesTab)
        # the tab's widgets, as the keys and the inspector act on them
        self.launch_tree, self.output_panel = self.nodes.launch_tree, self.nodes.pane
        self.detail_bar = self.nodes.detail
        self.nodes.trend_of = self.inspector.trend_of
        self.args_tab = self.query_one(ArgsTab)
        self.tabs = self.query_one(TabbedContent)
        self.status_bar = self.query_one("#status", Static)
        if ascii_terminal():  # app.tcss draws ASCII lines for this class
            self.add_class("-ascii")
        # the engine thread reads floods; a shorter GIL slice lets keypresses through sooner
        sys.setswitchinterval(0.001)
        self.engine = EngineThread()
        loop = asyncio.get_running_loop()
        loop.add_signal_handler(signal.SIGTERM, self.leaving.terminated)
        loop.add_signal_handler(signal.SIGHUP, self.leaving.terminal_hung_up)
        if self.starting is not None:
            # nothing runs yet: the tree shows the plan, every process waiting, and the
            # launch starts once it is on screen (on_ready)
            self.nodes.events.show_plan()
            self.status_bar.update(f"starting {Path(self.session.plan.file).name}...")
            self.launch_tree.focus()
            return
        self.wire_supervisor()

    def on_ready(self) -> None:
        """The first frame is on the terminal."""
        if self.starting is not None:
            self.starting.start()

    def on_server_started(self, message: ServerStarted) -> None:
        if message.error is not None:
            self.start_error = message.error
            self.exit(2, return_code=2)
        elif not self.quit_before_start:
            self.wire_supervisor()
            if self.starting is not None:  # once drawn, the launch's first process starts
                self.call_after_refresh(self.starting.plan_shown)

    def on_unmount(self) -> None:
        if self.starting is not None:
            self.starting.abandon()
        # any exit path that skipped the graceful shutdown still leaves no process behind
        if self.supervisor is not None:
            self.leaving.kill_all()
            self.engine.stop()

    def wire_supervisor(self) -> None:
        """Follows the launch: the session's server, through its client, wired to the
        panels; on mount, or once the session's server is up."""
        # built on the engine thread, whose loop its asyncio objects belong to
        remote: LaunchPort
        if self.given_port is not None:
            remote = self.given_port
        elif self.session_host is not None:
            # the session is on another machine: the protocol crosses an ssh link
            # sent what the output pane can show each second; what it cannot is
            # counted, and is in the log files over there
            try:
                remote = self.engine.submit(RemoteSupervisor.open_remote(
                    self.session_host, self.session_name, self.session,
                    self.scrollback, max_lines=max(12, self.size.height - PANE_CHROME),
                    interval=LINK_INTERVAL, link=self.remote_link)).result(timeout=120)
            except LaunchError as exc:  # the link failed between `attach` and here
                self.engine.stop()
                self.exit(2, return_code=2, message=f"tuilaunch attach: error: {exc}")
                return
        else:
            try:
                local = self.engine.submit(RemoteSupervisor.open(
                    self.session_name, self.session, self.scrollback,
                    max_lines=self.buffer.max_lines, interval=1 / DRAIN_HZ)).result(timeout=60)
            except LaunchError as exc:  # a server of another protocol version, one gone
                self.engine.stop()
                if self.server_process is not None:  # ours: what it started stops with it
                    self.server_process.terminate()
                self.start_error = str(exc)
                self.exit(2, return_code=2)
                return
            local.owner, local.keep_on_hangup = self.owner, self.keep_on_hangup
            remote = local
        remote.read_only = self.read_only
        self.view.supervisor = remote  # from here on, only its port (client/port.py)
        remote.subscribe(self.buffer)
        if isinstance(self.session, ServedSession):  # the form from the server's plan
            self.args_tab.show_form()
        tree = self.launch_tree
        self.nodes.events.show_plan()
        # what was printed before we came: shown, not news
        self.news_shown(self.view.show_events(remote.history, replaying=True), replaying=True)
        self.run_supervisor()
        self.drain_timer = self.set_interval(1 / DRAIN_HZ, self.drain)
        self.update_status()
        self.status.plan_warnings()
        # a tab picked while the server came up (3 pressed at once) stays on screen: the
        # tree takes the focus only where it shows (a focus in a hidden tab switches to it)
        if self.tabs.active == "nodes":
            tree.focus()
        self.navigation.shown(self.tabs.active or "nodes")
        if self.first_tab != "nodes":  # `attach --tab`
            self.call_after_refresh(self.navigation.tab, self.first_tab)
        elif self.first_typing is not None:  # `attach --type`: once the tree is laid out
            self.call_after_refresh(self.keyboard.type_first, self.first_typing)

    # --- the keys: each handed to the object it names -------------------------------------

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if self.keyboard.typing_to is not None:
            # every key is the node's while typing (ctrl+c, ctrl+p too): the footer offers
            # only ctrl+], not tuilaunch's stop or restart
            return False
        name = str(parameters[0]) if parameters else ""
        if action == "keyboard" and name == "refused":
            return self.read_only
        if self.read_only and (action, name) in READ_ONLY_REFUSES:
            return False
        if action == "keyboard":
            return self.keyboard.applies(name, parameters[1:])
        if action == "inspector":
            return self.inspector.applies(name, parameters[1:])
        if action == "navigation" and name == "find":
            # `/` into a list's filter: the tabs whose panel has no `/` of its own
            return self.tabs.active in ("services", "params")
        if action != "command":
            return True
        if self.supervisor is None or self.tabs.active != "nodes":
            return False
        return self.nodes.commands.applies(name, parameters[1:])

    def action_command(self, verb: str, *parameters: str) -> None:
        """s, r, t, ], [, a: the Nodes tab's selection's commands (nodes/commands.py)."""
        commands = self.nodes.commands
        if verb in ("stop", "restart", "start"):
            commands.command(verb)  # type: ignore[arg-type]
        elif verb == "lifecycle":
            commands.lifecycle(parameters[0])
        else:
            self.nodes.show_all()

    def action_keyboard(self, action: str, *parameters: str) -> None:
        self.keyboard.act(action, *parameters)

    def action_inspector(self, action: str) -> None:
        self.inspector.act(action)

    def action_navigation(self, action: str, *parameters: str) -> None:
        if action == "tab":
            self.navigation.tab(*parameters)
        elif action == "help":
            self.navigation.help()
        else:
            self.navigation.find()

    def action_leaving(self, action: str) -> None:
        self.leaving.act(action)

    async def action_quit(self) -> None:
        """Textual's quit (ctrl+q): as q."""
        self.leaving.request_quit()

    def action_leave_field(self) -> None:
        """Escape in a text field (screens/fields.py): back where the user was."""
        self.navigation.leave_field()

    def on_descendant_focus(self, event: events.DescendantFocus) -> None:
        self.navigation.focused(event.widget)

    @on(TabbedContent.TabActivated)
    def _tab_changed(self, event: TabbedContent.TabActivated) -> None:
        self.navigation.tab_activated(event.pane.id or "nodes")

    @on(LaunchTree.FiguresShown)
    def _figures_follow(self) -> None:
        self.inspector.figures_follow()

    def on_topics_panel_plot_asked(self, message: TopicsPanel.PlotAsked) -> None:
        self.inspector.plot(message.topic)

    def on_topics_panel_record_asked(self, message: TopicsPanel.RecordAsked) -> None:
        self.inspector.recordings.toggle(message.topic)

    def action_apply(self) -> None:
        """F5, from any tab: the form's values and the file as it is on disk now."""
        self.args_tab.apply()

    # --- command palette ---------------------------------------------------------------------

    def get_system_commands(self, screen: Screen[Any]) -> Iterable[SystemCommand]:
        for command in super().get_system_commands(screen):
            if command.title != "Keys":  # Textual's side panel took 30 of 80 columns
                yield command
        yield SystemCommand("Keys", "All the keys (F1, ?); esc closes", self.navigation.help)
        yield SystemCommand("Stop selected", "Stop the selected node or group",
                            lambda: self.action_command("stop"))
        yield SystemCommand("Restart selected", "Restart the selected node or group",
                            lambda: self.action_command("restart"))
        yield SystemCommand("Start selected", "Start the selected node or group",
                            lambda: self.action_command("start"))
        yield SystemCommand("Apply arguments", "Relaunch with the edited arguments",
                            self.action_apply)
        yield SystemCommand("Detach", "Leave the launch running (tuilaunch attach)",
                            self.leaving.detach)
        if not self.read_only:  # it changes what the session keeps: a view asks nothing
            yield SystemCommand("Black box: keep the last N s", "Switch the session's black "
                                "box on (asks the seconds; 0: off)",
                                lambda: self.inspector.act("black_box_keep"))
        yield SystemCommand("Black box: write now", "Write the last seconds kept into the "
                            "session's log folder (b)", lambda: self.inspector.act("black_box"))
        selected = self.nodes.commands.selected() if self.supervisor is not None else []
        if len(selected) == 1 and self.supervisor is not None:
            process = selected[0]
            state = self.supervisor.lifecycle.states.get(process)
            for transition in available_transitions(state):
                yield SystemCommand(
                    f"Lifecycle: {transition.replace('_', ' ')} {process}",
                    f"Ask the lifecycle node (now {state}) for this transition",
                    lambda t=transition, p=process: self.nodes.commands.lifecycle_transition(
                        p, t))
        if len(selected) == 1:
            yield SystemCommand("Topics of selected node", "The node's topics, rates and QoS",
                                self.inspector.node_topics)
            yield SystemCommand("Log level of selected node", "debug, info, warn, error, "
                                "fatal (asks)", self.inspector.log_level)
        for tab, title in (("nodes", "Nodes"), ("args", "Arguments"), ("services", "Services"),
                           ("params", "Parameters"), ("topics", "Topics")):
            yield SystemCommand(f"Open {title}", f"Show the {title} tab",
                                lambda tab=tab: self.navigation.tab(tab))


def launch_app(path: str, arguments: dict[str, str], log_dir: Path, name: str | None = None,
               positional: list[str] | None = None, placement: Placement | None = None,
               **options: Any) -> TuiLaunchApp:
    """`tuilaunch FILE`: the launch runs in a session server (`starting`: started already by
    the command line, else here), which loads the file; this TUI draws the plan it sends and
    is its first client, the owner (its quit stops the launch). `name`: `--name`, else the
    file's stem and a free number (LaunchError when taken). The tests open a launch's TUI
    through here too: the path users run."""
    starting = options.pop("starting", None) or spawn_session(
        path, arguments, name, log_dir, positional, owner=True, placement=None
        if placement is None else {"text": placement.text, "path": placement.machines.path,
                                   "share": placement.share})
    return make_app(path, arguments, log_dir, session_name=starting.name, owner=True,
                    served=True, start_server=starting, **options)


def make_app(path: str, arguments: dict[str, str], log_dir: Path, **options: Any)\
        -> TuiLaunchApp:
    """The one factory of the TUI, a client of session `session_name` (`launch_app` starts
    one; `attach` follows one that runs).
    `placement` (`--machines`): the tree labels each process with its machine. A session on
    another machine (`session_host`) is drawn from the plan its server sends: the launch file
    need not be readable here (`path` only names it)."""
    placement = options.pop("placement", None)
    served = options.pop("served", False)  # the file here is not the one the session runs
    if served or (options.get("session_host") is not None and not os.access(path, os.R_OK)):
        return TuiLaunchApp(ServedSession(path, arguments), log_dir, **options)
    return TuiLaunchApp(Session(path, arguments, placement=placement), log_dir, **options)
