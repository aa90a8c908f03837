"""The fleet TUI: several sessions, on several machines, in one screen
(`tuilaunch attach nuc:base arm:base local:sim`, or `arm:` for every session there).

The Nodes view has one tree per session, its root the session (`HOST:NAME`, `local:NAME`
here) with its live counts; the output pane and the header follow the session of the
selected row, and every key acts on that session alone. Each session is a `SessionView`
(session_view.py: the single TUI's pieces over one session, its tree, pane, commands,
keyboard and link words) with its own RemoteSupervisor and ssh link on the one engine
thread: a link lost to one robot greys its root, says why and that it reconnects
(RemoteSupervisor retries by itself), and its rows refuse keys with one line while the
others stay live. A robot unreachable at start is a root that says why and retries.

The Args, Services, Params and Topics tabs (`2`-`5`) are here, each session with its own
panels (tabs.py), showing the session of the selected row; F5 relaunches that session.
`s`, `r`, `t`, `]`, `[`, `i`, `g`, `c`, `o`, `L`, `b` are the selected view's (its
questions name the session), which work in a browser's page too; `p` in Topics is the
single TUI's plot screen (plots.py); `O` is the session in the single-session TUI (this
screen suspended meanwhile; `q`, `d` there come back here). A fleet TUI never stops a
session by leaving: `q` detaches from all.
"""

from __future__ import annotations

import asyncio
import contextlib
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from rich.text import Text
from textual import events, on, work
from textual.app import ComposeResult, SuspendNotSupported
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.notifications import SeverityLevel
from textual.widget import Widget
from textual.widgets import ContentSwitcher, Static, TabbedContent, TabPane, Tree

from ...client.port import LaunchPort
from ...client.remote_supervisor import RETRY_MOST
from ...engine.errors import LaunchError
from ...engine.plan.session import Session
from ...engine.run.engine_thread import EngineThread
from ..app import LaunchTabs
from ..key_order import KeyOrder
from ..output_store import OutputStore
from ..screens.output_panel import OutputPanel
from ..screens.topics_panel import TopicsPanel
from ..screens.tree_panel import LaunchTree, RowData, RowKind
from ..session_link import DRAIN_HZ, PANE_CHROME
from ..session_view import SessionView
from ..textual_compat import Footer
from ..toasts import OnceToasts
from .bindings import BINDINGS, FleetHelp
from .plots import FleetPlots
from .tabs import FleetTabs

NODES_ONLY = frozenset({"command", "all_output", "pane", "inspector", "resize"})
"""The actions of the Nodes tab: in another tab their keys are the panel's (or nothing)."""

FIRST_RETRY = 1.0
"""Seconds before a session that could not be opened is tried again (then doubling)."""


class FleetTree(LaunchTree):
    """A session's tree; the cursor moves on to the next session's tree past its end, and
    stops at the first session's root and the last session's last row (it never wraps
    from one robot onto another)."""

    def action_cursor_down(self) -> None:
        if self.cursor_line >= self.last_line and isinstance(self.app, FleetApp):
            self.app.step_tree(self, 1)
        else:
            super().action_cursor_down()

    def action_cursor_up(self) -> None:
        if self.cursor_line <= 0 and isinstance(self.app, FleetApp):
            self.app.step_tree(self, -1)
        else:
            super().action_cursor_up()


class FleetApp(KeyOrder):
    """One TUI over several sessions (see the module's docstring). Its keys are handled one
    after the other, as the single TUI's (key_order.py): `3/reset` typed at once over ssh
    filters the services, never stopping a node with its `s`. A session's keys are its
    view's (session_view.py): the app picks the view, lays the views out, is their host."""

    CSS_PATH = "../screens/app.tcss"  # the single-session TUI's look
    TITLE = "tuilaunch"
    CSS = """
    #fleet-trees { width: 36; border-right: tall $panel; }
    #fleet-trees FleetTree { width: 100%; height: auto; border-right: none; }
    #fleet-split { height: 1fr; }
    #fleet-panes { width: 1fr; }
    /* a phone (a browser 390 px wide: ~40 columns): the trees above the pane, each whole */
    FleetApp.-narrow #fleet-split { layout: vertical; }
    FleetApp.-narrow #fleet-trees { width: 100%; height: 1fr; border-right: none;
                                    border-bottom: tall $panel; }
    FleetApp.-narrow #fleet-panes { width: 100%; height: 1fr; }
    """
    NARROW = 70
    """Columns below which the trees go above the pane (a phone's browser)."""
    BINDINGS = BINDINGS
    quitting = False
    """A fleet view never stops its sessions by leaving."""

    def __init__(self, addresses: list[tuple[str | None, str]], scrollback: int = 5000,
                 read_only: bool = False,
                 ports: Sequence[tuple[Session, LaunchPort]] | None = None) -> None:
        """`addresses`: (host or None for here, session name), in the order shown;
        `read_only`: every session's client refuses what would change it (a wall screen);
        `ports`: each session's plan and port handed in (an in-memory one, in tests/unit),
        followed as its client would be, without opening one."""
        super().__init__()
        self.read_only = read_only
        self.animation_level = "none"  # every frame is bytes over ssh
        self.scrollback = scrollback
        given = list(ports or ())
        self.members: list[SessionView] = []
        for i, (host, name) in enumerate(addresses):
            store = OutputStore(scrollback=scrollback, all_scrollback=scrollback * 4)
            label = f"{host or 'local'}:{name}"
            tree = FleetTree(id=f"fleet-tree-{i}")
            tree.root.set_label(Text(f"{label} connecting...", style="dim"))
            pane = OutputPanel(store, Path.cwd(), max_lines=scrollback, id=f"fleet-pane-{i}")
            session, port = given[i] if i < len(given) else (None, None)
            self.members.append(SessionView(label, host, name, tree, pane, store, self,
                                            session, port))
        self.current = self.members[0]
        self.plots = FleetPlots(self, self.members)
        self.session_tabs = FleetTabs(self.members, self.plots)
        self._status_text = ""
        self._detail_text = ""
        self.detached = False
        self._resumed_at = 0.0
        """When this screen came back from the TUI it waited for (O): keys read before
        then were typed for that TUI, never for this one."""
        self.toasts = OnceToasts()

    def notify(self, message: str, *, title: str = "",
               severity: SeverityLevel = "information", timeout: float | None = None,
               markup: bool = True) -> None:
        """A toast, unless the same one is on screen (toasts.py, as the single TUI's): a
        group's command failing on four nodes of an unreachable robot says it once."""
        shown_for = self.NOTIFICATION_TIMEOUT if timeout is None else timeout
        if self.toasts.new(message, title, severity, shown_for):
            super().notify(message, title=title, severity=severity, timeout=timeout,
                           markup=markup)

    # --- layout ------------------------------------------------------------------------

    def compose(self) -> ComposeResult:
        yield Static("", id="status")
        with LaunchTabs(initial="nodes", id="fleet-tabs"):
            with TabPane("1 Nodes", id="nodes"), Vertical(id="nodes-tab"):
                yield Static("", id="detail")
                with Horizontal(id="fleet-split"):
                    with VerticalScroll(id="fleet-trees"):
                        for member in self.members:
                            yield member.tree
                    with ContentSwitcher(id="fleet-panes", initial=self.members[0].pane.id):
                        for member in self.members:
                            yield member.pane
            for tab, title in (("args", "2 Args"), ("services", "3 Services"),
                               ("params", "4 Params"), ("topics", "5 Topics")):
                with TabPane(title, id=tab):
                    yield from self.session_tabs.compose(tab)
        yield Footer()

    def on_mount(self) -> None:
        self.status_bar = self.query_one("#status", Static)
        self.detail_bar = self.query_one("#detail", Static)
        self.switcher = self.query_one("#fleet-panes", ContentSwitcher)
        self.nodes_tab = self.query_one("#nodes-tab", Vertical)
        self.tabs = self.query_one(LaunchTabs)
        self.engine = EngineThread()
        for member in self.members:
            self.follow(member)
        self.set_interval(1 / DRAIN_HZ, self.drain)
        self.members[0].tree.focus()
        self.update_status()

    def on_resize(self, event: events.Resize) -> None:
        narrow = event.size.width < self.NARROW
        self.set_class(narrow, "-narrow")
        if narrow:  # the trees above the panes take the whole width, whatever `<` `>` set
            self.query_one("#fleet-trees").styles.width = None

    async def show_typing_line(self, line: Widget) -> None:
        await self.nodes_tab.mount(line, before="#fleet-split")

    # --- the members' links ------------------------------------------------------------

    @work(exit_on_error=False)
    async def follow(self, member: SessionView) -> None:
        """Opens the member's session (again and again, with backoff, while it cannot be
        reached), then follows it until it ends or the fleet detaches."""
        wait = FIRST_RETRY
        while member.supervisor is None and not self.detached:
            try:
                member.supervisor = await self.engine.run(member.open_port(
                    self.scrollback, max(12, self.size.height - PANE_CHROME), 1 / DRAIN_HZ))
            except LaunchError as exc:
                member.problem = f"{exc.message}; retrying (R: now)"
                member.refresh_root()
                self.update_status()
                member.wake = asyncio.Event()
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(member.wake.wait(), wait)
                wait = min(wait * 2, RETRY_MOST)
        supervisor = member.supervisor
        if supervisor is None:
            return
        member.followed(supervisor, supervisor.log_dir)
        self.session_tabs.followed(member)
        self.session_tabs.news(member, member.show_events(supervisor.history,
                                                          replaying=True))
        self.update_status()
        await self.engine.run(supervisor.run(keep_alive=True))
        if self.detached:
            return
        member.ended = True
        member.problem = "ended" if not supervisor.lost else "the session's server is gone"
        self.session_tabs.news(member, member.drain())
        member.refresh_root()
        self.update_status()
        if all(m.ended for m in self.members):
            self.exit(0)

    def drain(self) -> None:
        for member in self.members:
            if member.supervisor is None:
                continue
            self.session_tabs.news(member, member.drain())
            # a link lost, back, or silent for one more second: the root says it
            member.refresh_root()
            telling = member.tell_shown()  # the lines of its pane's node, over a link
            if telling is not None:
                self.engine.submit(telling)
        self.update_status()
        self.update_detail()

    # --- the selection -------------------------------------------------------------------

    def on_descendant_focus(self, event: events.DescendantFocus) -> None:
        """The session of the tree with the focus is the selected one."""
        member = view_of(self.members, event.widget)
        if member is not None and member is not self.current:
            self.current = member
            self.switcher.current = member.pane.id
            if self.tabs.active != "nodes":
                self.session_tabs.shown(self.tabs.active, member)
            self.update_status()
        if member is not None:
            self.update_detail()

    @on(Tree.NodeHighlighted)
    def _highlighted(self, event: Tree.NodeHighlighted[RowData]) -> None:
        member = view_of(self.members, event.control)
        if member is None:
            return
        data = event.node.data
        if data is not None and data.kind == RowKind.PROCESS:
            member.pane.show_view(data.ref)
        elif data is not None and data.kind == RowKind.ALL:
            member.pane.show_view(None)
        self.update_detail()
        self.refresh_bindings()  # the keys that apply follow the row

    def step_tree(self, tree: FleetTree, step: int) -> None:
        """Up from a tree's first row, down from its last: the neighbouring session's."""
        member = view_of(self.members, tree)
        if member is None:
            return
        index = self.members.index(member) + step
        if not 0 <= index < len(self.members):
            return  # the first or last row of all: the cursor stays (no wrap)
        target = self.members[index].tree
        target.focus()
        target.cursor_line = 0 if step > 0 else target.last_line
        target.scroll_to_node(target.cursor_node or target.root)

    def action_jump(self, step: int) -> None:
        """`}`, `{`: the next (previous) session's root, as k9s switches context; at the
        last (first) session the cursor stays."""
        index = self.members.index(self.current) + step
        if not 0 <= index < len(self.members):
            return
        target = self.members[index].tree
        if self.tabs.active != "nodes":
            self.action_tab("nodes")
        target.focus()
        target.cursor_line = 0
        target.scroll_to_node(target.root)

    # --- the tabs ------------------------------------------------------------------------

    def action_tab(self, tab: str) -> None:
        """1, 3, 4, 5: the tab, for the session of the selected row; the cursor where the
        tab's work starts, so the keys typed next go there."""
        if self.tabs.active != tab:
            self.tabs.active = tab
        self.session_tabs.shown(tab, self.current)
        self._go_home(tab)
        self.refresh_bindings()

    def _go_home(self, tab: str) -> None:
        home: Widget | None = self.current.tree if tab == "nodes" else \
            self.session_tabs.home(tab, self.current)
        if home is not None:
            self.screen.set_focus(home)

    @on(TabbedContent.TabActivated)
    def _tab_clicked(self, event: TabbedContent.TabActivated) -> None:
        tab = event.pane.id or "nodes"
        if tab != self.session_tabs.active:  # a click on the tab: as its key
            self.action_tab(tab)

    def action_apply(self) -> None:
        """F5, from any tab: the selected session relaunched with its Args tab's values and
        its file as it is now (as the single TUI's F5)."""
        member = self.current
        if member.keys_reach():
            self.session_tabs.of(member).args.apply()

    @on(TopicsPanel.PlotAsked)
    def _plot_asked(self, message: TopicsPanel.PlotAsked) -> None:
        """p on a topic: the single TUI's plot, over the selected session's link."""
        message.stop()
        member = self.current
        if member.keys_reach():
            self.plots.open(member, message.topic)

    # --- keys: the selected session's view acts ---------------------------------------------

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if any(m.keyboard.typing_to is not None for m in self.members):
            # every key is the node's while typing (ctrl+c too): the footer offers ctrl+]
            return False
        name = str(parameters[0]) if parameters else ""
        if action == "keyboard":
            return self.current.keyboard.applies(name, parameters[1:])
        if action in NODES_ONLY and self.tabs.active != "nodes" and name != "black_box":
            # `/` into the tab's filter; the Nodes tab's other keys are not this tab's
            return action == "pane" and name == "search"
        if action == "inspector" and name != "black_box":
            return True if self.current.selected_process() else None
        if action == "command" and name != "lifecycle" and self.current.out_of_reach() is None:
            # greyed as in the single TUI (nothing to stop); a session out of reach keeps
            # them, to say why in one line
            return self.current.commands.applies(str(parameters[0]), ())
        return True

    def action_leave_field(self) -> None:
        """Escape in a text field: back where the tab's work starts."""
        if self.tabs.active == "nodes":
            self.current.pane.action_clear_search()
        self._go_home(self.tabs.active)

    def action_command(self, verb: str, *parameters: str) -> None:
        """s, r, t on the selected rows of the selected session; `]` (up), `[` (down) on its
        lifecycle node, which say why when they cannot (session_view.py)."""
        if verb == "lifecycle":
            self.current.lifecycle(parameters[0])
        else:
            self.current.command(verb)  # type: ignore[arg-type]
        self.update_detail()

    def action_keyboard(self, action: str, *parameters: str) -> None:
        """i, g, c: the single TUI's keyboard, on the selected session (keyboard.py)."""
        self.current.keyboard.act(action, *parameters)

    def action_inspector(self, action: str) -> None:
        """o, L, b: the single TUI's inspector keys, on the selected session: its node's
        topics in its Topics tab, its node's log level, its black box written."""
        node = self.current.inspect(action)
        if node is not None:  # o: the node's topics
            self.session_tabs.of(self.current).topics.show_node(node)
            self.action_tab("topics")

    @on(OutputPanel.StampsWanted)
    def _stamps_wanted(self, message: OutputPanel.StampsWanted) -> None:
        self.current.stamps_wanted(message)  # the keys reach the selected session's pane

    def action_all_output(self) -> None:
        self.current.pane.show_view(None)

    def action_pane(self, name: str) -> None:
        if self.tabs.active != "nodes":  # `/` in another tab: into its filter field
            field = self.session_tabs.filter_field(self.tabs.active, self.current)
            if field is not None:
                self.screen.set_focus(field)
            return
        getattr(self.current.pane, f"action_{name}")()

    def action_reconnect(self) -> None:
        self.current.reconnect()

    def action_help(self) -> None:
        self.push_screen(FleetHelp())

    def action_resize(self, step: int) -> None:
        """`<`, `>`: the trees' column narrower or wider (the panes keep the rest)."""
        trees = self.query_one("#fleet-trees")
        if not self.has_class("-narrow"):  # above the panes, the trees are full width
            trees.styles.width = max(12, min(trees.outer_size.width + step,
                                             max(self.size.width - 20, 12)))

    def action_open_session(self, tab: str = "nodes") -> None:
        """The selected session in the single-session TUI (all its tabs), on `tab`, this
        screen suspended meanwhile; `d` (or `q`) there comes back."""
        member = self.current
        if member.out_of_reach() is not None:
            self.notify(f"{member.label}: {member.out_of_reach()}", severity="warning")
            return
        args = ("attach", member.address, "--tab", tab)
        try:
            with self.suspend():
                subprocess.run([sys.executable, "-P", "-m", "tuilaunch", *args])
        except SuspendNotSupported:  # a browser's page (tuilaunch serve) has no terminal
            self.notify(f"this view cannot hand its terminal over: run tuilaunch "
                        f"{' '.join(args)} in one", severity="warning")
            return
        finally:
            self._resumed_at = time.monotonic()
        self.refresh()

    async def on_event(self, event: events.Event) -> None:
        if isinstance(event, events.Key) and not event.is_forwarded and \
                event.time < self._resumed_at:
            return  # read before the other TUI took the terminal: typed for it
        await super().on_event(event)

    def action_quit_fleet(self) -> None:
        """Leaves every session running: a fleet view is a watcher, each robot's launch its
        own (`tuilaunch stop HOST:NAME ...` stops them)."""
        self.detached = True
        for member in self.members:
            if member.supervisor is not None and not member.ended:
                self.engine.submit(member.supervisor.detach())
        self.exit(0)

    def on_unmount(self) -> None:
        self.detached = True
        for member in self.members:
            if member.supervisor is not None:
                try:
                    self.engine.call(member.supervisor.kill_all)
                except Exception:
                    pass  # its loop ended already
        self.engine.stop()

    # --- the header ---------------------------------------------------------------------------

    def update_status(self) -> None:
        member = self.current
        others = len(self.members) - 1
        why = member.out_of_reach() or member.silence()
        what = why if why is not None else member.counts_text()
        file = Path(member.session.plan.file).name if member.supervisor else ""
        label = f"{member.label} read-only" if self.read_only else member.label
        line = f"[{label}] {file}  {what}  ({others + 1} sessions; O: this one in full)"
        if line != self._status_text:
            self._status_text = line
            self.status_bar.update(Text(line))

    def update_detail(self) -> None:
        """The selected row in full; on a session's root, the session as the root says."""
        text = self.current.detail_text()
        if text != self._detail_text:
            self._detail_text = text
            self.detail_bar.update(Text(text))


def view_of(views: list[SessionView], widget: object) -> SessionView | None:
    """The view whose tree `widget` is."""
    return next((v for v in views if v.tree is widget), None)
