"""One session as the TUI shows it and acts on it: a `SessionView`.

A view owns one session's state (its port, plan, output store, event buffer, the stops it
asked, its link's words), its Nodes widgets (tree and pane) and their behaviour: how its
events show (NodeEvents), its selection's commands and lifecycle steps (SelectionCommands,
whose group stops ask first), its keyboard (`i`, `g`, `c`: NodeKeyboard, its bursts held),
its log levels, its black box, the stamps its link did not send. The view is itself the
host those pieces need (the keyboard's KeyboardHost, the tree's NodesHost, the Args tab's
ArgsHost): one adapter, whatever app lays the view out. What it needs of that app is a
small `ViewHost`; what it says it says on the app its tree is on, naming the session in a
fleet. The single TUI (app.py) holds one view, its `label` empty (alone on screen: its
lines name no session, its root is the launch's); a fleet view (fleet/app.py) one each.

A composition object, not a Widget: each app lays the view's widgets out its own way. The
single TUI puts the tree and pane side by side in its Nodes tab (nodes/tab.py, with the
detail line); a fleet view stacks N trees in one scrolling column and switches panes
beside them, so a session's tree and pane are not one box of the screen; a Widget holding
both would change that layout. The rules (a group stop asks, a session out of reach refuses its
keys with one line, a link's silence on its root, bursts held after `i`) are the view's
code, so each session of a fleet keeps them by construction.
"""

from __future__ import annotations

import asyncio
import os
import time
from collections.abc import Coroutine
from pathlib import Path
from typing import Any, Protocol, TypeVar

from rich.text import Text
from textual.app import App
from textual.binding import Binding
from textual.notifications import SeverityLevel
from textual.widget import Widget
from textual.widgets import TabbedContent

from ..client.link import relink_words
from ..client.port import LaunchPort, Verb
from ..client.remote_supervisor import LINK_INTERVAL, RemoteSupervisor
from ..client.served_session import ServedSession
from ..engine.plan.session import Session
from ..engine.run.engine_thread import EngineThread
from ..engine.run.event_buffer import EventBuffer
from ..engine.run.events import LIVE_STATES, Event, Output, Reading, Typing
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary.forward import Forward
from ..engine.run.vocabulary.request import Request
from .inspect.log_levels import LogLevels
from .inspect.recording import Recordings
from .keys.keyboard import NodeKeyboard
from .nodes.commands import SelectionCommands
from .nodes.events import Batch, NodeEvents
from .nodes.gaps import GapReader
from .output_store import OutputStore
from .screens.output_panel import OutputPanel
from .screens.tree_panel import LaunchTree, RowKind
from .status_line import counts_words, silence_words

R = TypeVar("R")

COMMAND_BINDINGS = [
    Binding("s", "command('stop')", "Stop", tooltip="Stop the selected node or group"),
    Binding("r", "command('restart')", "Restart",
            tooltip="Restart the selected node or group"),
    Binding("t", "command('start')", "Start", tooltip="Start the selected node or group"),
]
"""The keys of a view's selection's commands (`command`), the same in every app."""


def lifecycle_bindings(show: bool = True) -> list[Binding]:
    """`]` and `[`: the selected lifecycle node a step up or down (`command('lifecycle')`),
    the same in every app; `show`: in the footer (a fleet's has no room for them)."""
    return [
        Binding("right_square_bracket", "command('lifecycle', 'up')", "Lifecycle up",
                show=show,
                tooltip="Configure an unconfigured, activate an inactive lifecycle node"),
        Binding("left_square_bracket", "command('lifecycle', 'down')", "Lifecycle down",
                show=show, tooltip="Deactivate an active, clean up an inactive lifecycle node"),
    ]


class ViewHost(Protocol):
    """What a view needs of the app that lays it out."""

    # read, never set, here: properties, so an app's own attributes fit
    @property
    def engine(self) -> EngineThread: ...
    @property
    def read_only(self) -> bool: ...
    @property
    def quitting(self) -> bool:
        """Whether the app is stopping the launch (a fleet never does)."""
    @property
    def tabs(self) -> TabbedContent:
        """Its tabs: the Nodes tab (`nodes`) shows the views' trees."""

    def update_status(self) -> None: ...

    async def show_typing_line(self, line: Widget) -> None:
        """Puts the line taking the keys above the trees and panes."""


class SessionView:
    """One session, shown by `tree` and `pane`: `label` is how its root names it
    (HOST:NAME, local:NAME; empty: the session is alone on screen), `host` its machine
    (None: this computer)."""

    def __init__(self, label: str, host: str | None, name: str, tree: LaunchTree,
                 pane: OutputPanel, store: OutputStore, screen: ViewHost,
                 session: Session | None = None, port: LaunchPort | None = None) -> None:
        self.label, self.host, self.name = label, host, name
        self.who = label
        """The session a question names (empty: the one on screen needs no name)."""
        self.tree, self.pane, self.store, self.screen = tree, pane, store, screen
        self.launch_tree = tree
        self.session: Session = session or ServedSession("?", {})
        """Its plan: the one its server runs, sent over the link (a test hands its own)."""
        self.given_port = port
        """A port handed in (an in-memory one, in tests/unit): followed without opening."""
        self.buffer = EventBuffer(max_lines=2500)
        self.supervisor: LaunchPort | None = None
        self.problem: str | None = None
        """Why the session is not followed now: cannot be reached (retrying), or ended."""
        self.ended = False
        self.wake: asyncio.Event | None = None
        """Set by R: the next try to reach a session never reached, now."""
        self.asked_to_stop: set[str] = set()
        """The stops this client asked for (a restart's): their exit is no failure."""
        self.own_relaunch: list[str] | None = None
        self.events = NodeEvents(
            tree, store, lambda: self.session.plan,
            lambda: None if self.supervisor is None else self.supervisor.states,
            lambda: {} if self.supervisor is None else self.supervisor.lifecycle.states,
            lambda: screen.quitting, self.asked_to_stop)
        self.keyboard = NodeKeyboard(self)
        self.commands = SelectionCommands(tree, self, tree, store, who=label)
        self.recordings = Recordings(self, self.request)  # `b`: its black box written
        # what its link did not send (`T`, `f`: stamps), read back; said naming it
        self.gaps = GapReader(store, pane, lambda: screen.engine, lambda: self.supervisor,
                              self.notify)
        self._log_levels: LogLevels | None = None

    # --- as the host of the single TUI's pieces ----------------------------------------------

    app = Forward[App[Any]]("tree")
    quitting = Forward[bool]("screen")
    engine = Forward[EngineThread]("screen")
    read_only = Forward[bool]("screen")

    @property
    def address(self) -> str:
        """As the command line takes it."""
        return self.name if self.host is None else f"{self.host}:{self.name}"

    def client(self) -> LaunchPort:
        """The session's client; SessionError (a LaunchError) before it is followed (a key
        pressed, a tab shown, while its server still comes up)."""
        if self.supervisor is None:
            raise SessionError((self.problem or "not connected") if self.label else
                               f"session {self.name} is not followed yet")
        return self.supervisor

    def running(self) -> list[str]:
        if self.supervisor is None:
            return []
        return [p for p, s in self.supervisor.states.items() if s in LIVE_STATES]

    def over_link(self) -> LaunchPort | None:
        supervisor = self.supervisor
        return supervisor if supervisor is not None and supervisor.host is not None else None

    def nodes_shown(self) -> bool:
        return self.screen.tabs.active == "nodes"

    def unavailable(self) -> str | None:
        """Why keys cannot act on this session now, as said (None: they can)."""
        if not self.label:
            # alone on screen, a link lost is said by the request that fails (a fleet
            # greys the session's root instead, and its keys say why)
            return "the session is not followed yet" if self.supervisor is None else None
        why = self.out_of_reach()
        if why is None:
            return None
        return "the session ended" if self.ended else \
            f"{why}; its nodes take no keys until it is back"

    def selected_process(self) -> str | None:
        node = self.tree.cursor_node
        if node is None or node.data is None or node.data.kind != RowKind.PROCESS:
            return None
        return node.data.ref

    def notify(self, message: str, *, severity: SeverityLevel = "information",
               title: str = "") -> None:
        self.app.notify(f"{self.label}: {message}" if self.label else message,
                        severity=severity, title=title)

    async def show_typing_line(self, line: Widget) -> None:
        await self.screen.show_typing_line(line)

    def update_status(self) -> None:
        self.screen.update_status()

    def drain(self) -> Batch:
        """The events waiting now, shown (`show_events`): what they changed."""
        return self.show_events(self.buffer.drain())

    def describe_waiting(self) -> None:
        """After a relaunch: each process not started yet says why on its row (alone on
        screen); a fleet's root says the new plan's counts."""
        if self.label:
            self.refresh_root()
        else:
            self.events.describe_waiting()

    # --- its link ----------------------------------------------------------------------------

    async def open_port(self, scrollback: int, lines: int, interval: float) -> LaunchPort:
        """On the engine thread: the session's RemoteSupervisor (or the port handed in);
        `interval`: its drain's, for a session on this computer."""
        if self.given_port is not None:
            return self.given_port
        if self.host is None:
            return await RemoteSupervisor.open(self.name, self.session, scrollback,
                                               max_lines=lines, interval=interval)
        return await RemoteSupervisor.open_remote(
            self.host, self.name, self.session, scrollback, max_lines=lines,
            interval=LINK_INTERVAL)

    async def request(self, request: Request[R]) -> R:
        """A request to the session, from its panels (SessionError while out of reach)."""
        why = self.out_of_reach()
        if why is not None or self.supervisor is None:
            raise SessionError(f"{self.label}: {why or 'not connected'}")
        return await self.engine.run(self.supervisor.request(request))

    def out_of_reach(self) -> str | None:
        """Why the session cannot be acted on now (None: it can)."""
        if self.supervisor is None or self.ended:
            return self.problem or "not connected"
        return self.supervisor.link_lost

    def reconnect(self) -> None:
        """Now, rather than at the next try: a dropped link, or a session never reached."""
        if self.supervisor is not None:
            self.engine.call(self.supervisor.retry_now)
        elif self.wake is not None:
            self.wake.set()

    def silence(self) -> str | None:
        """`no word from arm for 7 s`, as the single TUI's status line says it."""
        supervisor = self.supervisor
        return None if supervisor is None or self.ended else silence_words(supervisor)

    def counts_text(self) -> str:
        """Its processes by state, as the single TUI's status line counts them."""
        if self.supervisor is None:
            return ""
        return counts_words(self.session.plan, self.tree.states, self.supervisor.states)

    def root_label(self) -> Text:
        """The session's root row: its address and live counts; greyed, with why,
        while it cannot be reached."""
        label = Text(self.label, style="bold")  # its file is in the header: room for counts
        why = self.out_of_reach()
        if self.ended:
            label.append(f" {why}  {self.counts_text()}", "italic")
            label.stylize("dim")
        elif why is not None:
            # a link that dropped reconnects by itself (an attempt under way says so, with
            # the latest reason); one never made says it retries
            label.append(f" {why}" + (f"; {relinking(self.supervisor)}"
                                      if self.supervisor else ""), "italic")
            label.stylize("dim")
        elif self.silence() is not None:
            # what it shows may be old: said first, before the counts it last sent
            label.append(f" {self.silence()}", "bold yellow")
            label.append(f"  {self.counts_text()}")
        else:
            label.append(f"  {self.counts_text()}")
        return label

    def refresh_root(self) -> None:
        label = self.root_label()
        if label.plain != str(self.tree.root.label):  # an unchanged row is not sent again
            self.tree.root.set_label(label)

    def detail_text(self) -> str:
        """The selected row in full; on the root, the session as the root says."""
        node = self.tree.cursor_node
        if node is None or node is self.tree.root:
            return self.root_label().plain
        return self.tree.describe(node)

    def tell_shown(self) -> Coroutine[Any, Any, None] | None:
        """The call telling the session whose lines its pane shows (all for all nodes),
        when it must be told: as the single TUI, only over a link (a session here sends
        its lines to a screen at its drain rate, which costs no link)."""
        supervisor = self.over_link()
        if supervisor is None or self.ended or supervisor.link_lost is not None:
            return None
        shown = self.pane.view.process
        return None if shown == supervisor.only else supervisor.show(shown)

    # --- events ------------------------------------------------------------------------------

    def show_events(self, events: list[Event], replaying: bool = False) -> Batch:
        """The events of a drain into the tree and pane (NodeEvents), at once: the single
        TUI's and each fleet session's alike. `replaying`: what happened before this client
        came, shown but no news. Returns what they changed, with the readings for the
        tabs, for the app to act on in the same call: no frame has a row's news without
        its counts."""
        # a flood's lines are the tree's and the pane's only: the keyboard is handed the
        # rest, the app what they changed
        said = [event for event in events if not isinstance(event, Output)]
        news = self.keyboard.take_events(said)  # who types where: the keyboard's
        shown = self.events.show([event for event in events
                                  if not isinstance(event, (Reading, Typing))])
        shown.readings = [event for event in news if isinstance(event, Reading)]
        shown.news = len(shown.readings) < len(news)
        if replaying:
            self.events.show_lifecycle()  # the states it has now, newer than the replay's
        if shown.lines:
            self.pane.append(shown.lines)
        self.pane.flush()
        if self.label:
            # a fleet's session: a respawn's wait counts down on its row each tick (only
            # changed rows drawn), its root says its counts (the single TUI's Nodes tab
            # counts down once a second, its status line says the counts)
            if shown.counting:
                self.events.count_down()
            if events:
                self.refresh_root()
        self.keyboard.events_shown(said)  # a node typed into that ended gives the keys back
        return shown

    def show_plan(self) -> None:
        """The session's plan as the tree's children, its root the session."""
        self.events.show_plan()
        self.refresh_root()

    def followed(self, port: LaunchPort, log_dir: Path) -> None:
        """The session's port is open: its history shown, its events from now on taken."""
        self.problem = None
        # `w` writes where the single TUI would for this session (its log folder here, or
        # a folder named after its machine), not into the folder the fleet was started in
        self.pane.save_dir = pane_save_dir(log_dir, self.host, self.name)
        port.read_only = self.read_only  # refused by the client, said in one line
        port.subscribe(self.buffer)
        self.show_plan()

    # --- its keys ----------------------------------------------------------------------------

    def keys_reach(self) -> bool:
        """Whether keys can act on the session now; else one line says why."""
        why = self.unavailable()
        if why is not None or self.supervisor is None:
            self.notify(why or "not connected", severity="warning")
            return False
        return True

    def command(self, verb: Verb) -> None:
        """s, r, t on the selected rows, and nothing else: the single TUI's commands (a stop
        or restart of more than one asks, naming the session)."""
        if self.keys_reach():
            self.commands.command(verb)

    def lifecycle(self, direction: str) -> None:
        """`]` (up), `[` (down) on the selected lifecycle node, from the state the steps
        typed before lead to (the single TUI's steps)."""
        supervisor = self.supervisor
        if not self.keys_reach() or supervisor is None:
            return
        selected = self.commands.selected()
        states = supervisor.lifecycle.states
        if len(selected) != 1 or selected[0] not in states:
            self.notify(f"{']' if direction == 'up' else '['} steps one lifecycle node: "
                        "select it", severity="warning")
            return
        step = self.commands.lifecycle_step(direction)
        if step is None:
            self.notify(f"{selected[0]} is {states.get(selected[0])}: no step "
                        f"{'up' if direction == 'up' else 'down'} from there",
                        severity="warning")
            return
        self.commands.lifecycle_transition(*step)

    def inspect(self, action: str) -> str | None:
        """o, L, b: the single TUI's inspector keys on this session: its black box written,
        its node's log level asked; for `o` (node_topics), the ROS name of the selected
        node, whose topics the app shows."""
        if not self.keys_reach():
            return None
        if action == "black_box":
            self.app.run_worker(self.recordings.black_box_now(), group="recording",
                                exit_on_error=False)
            return None
        process = self.selected_process()
        if process is None:
            return None
        node = self.store.node_name(self.session.plan, process)  # its ROS name
        if action == "node_topics":
            return node
        if self._log_levels is None:
            self._log_levels = LogLevels(self.app, self.request, self.asked_to_stop,
                                         f"{self.label}: ")
        self._log_levels.ask(process, node)
        return None

    def stamps_wanted(self, message: OutputPanel.StampsWanted) -> None:
        """T, f: the ROS stamps of the lines a link sent without them, read first (the
        single TUI's GapReader)."""
        port = self.over_link()
        if port is None or self.gaps.stamps_known(port, message.shown):
            message.then()
            return
        self.app.run_worker(self._read_stamps(port, message), group="stamps",
                            exit_on_error=False)

    async def _read_stamps(self, port: LaunchPort, message: OutputPanel.StampsWanted) -> None:
        read = await self.gaps.read_stamps(port, message.shown)
        if read is not None:  # else not read, and said: the key still does its part
            self.drain()  # the lines sent before the answer
            self.gaps.fill_stamps(*read)
        message.then()


def pane_save_dir(log_dir: Path, host: str | None, name: str) -> Path:
    """Where `w` writes a pane: the launch's log folder, which is on this computer, unless
    the session runs on another machine (its log folder is there; a pane is saved here, in
    a folder named after that machine and session)."""
    if host is None:
        return log_dir
    base = os.environ.get("ROS_LOG_DIR") or os.path.join(
        os.environ.get("ROS_HOME") or os.path.expanduser("~/.ros"), "log")
    return Path(base) / f"tuilaunch-{host}-{name}"


def relinking(port: LaunchPort) -> str:
    since = port.attempt_since
    words = relink_words(port.attempt, None if since is None else time.monotonic() - since)
    if words == "reconnecting":  # between tries (or one just begun): R tries now
        return "reconnecting (R: now)"
    last = port.lost_reason or ""
    return words + (f", last: {last}" if last and last not in (port.link_lost or "") else "")
