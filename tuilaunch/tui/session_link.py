"""The app's state and its link to the engine: supervisor wiring, engine events.

The session itself (its port, buffer, tree and pane, its commands and its keyboard) is the
app's one `SessionView` (session_view.py, `view`, made by app.py), as each session of a
fleet view is one. Engine events reach the UI through the view's EventBuffer drained on a
timer, so a flood from a node costs one batched write per pane per tick: each tick's
batch goes into the tree and pane by the view (as each fleet session's does), the status
line in the same call, the readings a tab asked for to the inspector. The App
constructor does no I/O: the session's client starts in on_mount.
"""

from __future__ import annotations

import asyncio
import os
import subprocess
import time
from collections.abc import Callable, Coroutine
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from rich.text import Text
from textual import on, work
from textual.app import App, ScreenStackError
from textual.notifications import SeverityLevel
from textual.timer import Timer
from textual.widget import Widget
from textual.widgets import Static, TabbedContent, Tree
from textual.worker import Worker, WorkerState

from ..client.port import LaunchPort
from ..client.read_only import ReadOnlyError
from ..engine.plan.session import Session
from ..engine.run.engine_thread import EngineThread
from ..engine.run.event_buffer import EventBuffer
from ..engine.run.events import Event
from ..engine.run.machines.remote import RemoteLink
from .arguments import ArgsTab
from .nodes.events import Batch
from .nodes.tab import NodesTab
from .output_store import OutputStore
from .screens.output_panel import OutputPanel
from .screens.tree_panel import LaunchTree, RowData
from .server_start import ServerStart, leave_now
from .toasts import OnceToasts

if TYPE_CHECKING:
    from .screens.topics_panel import TopicsPanel

# the UI's tick: events are taken from the engine this often; the output pane repaints at
# most PANE_FPS times a second and only when what it shows changed, so a terminal over ssh
# gets little more than what changed on screen
DRAIN_HZ = 10
PANE_FPS = 1.0
PANE_CHROME = 6
"""Rows of the screen that are not the output pane (status, tabs, detail, the pane's own
status line, footer): a display over a link is sent a pane's worth of lines a second, as
the pane repaints once a second and shows no more."""
ENDED_ELSEWHERE_PAUSE = 3.0
"""Seconds a client shows that its session was stopped elsewhere before it leaves."""


class KeyboardNews(Protocol):
    """What the link tells the keyboard (keyboard.py's NodeKeyboard) of each batch."""

    typing_to: str | None

    def take_events(self, events: list[Event]) -> list[Event]: ...
    def events_shown(self, events: list[Event]) -> None: ...
    def status_notes(self, link_lost: bool) -> list[str]: ...


class StatusWords(Protocol):
    """What the link tells the status line (status_line.py's StatusLine)."""

    drawn: str

    def update(self) -> None: ...
    def signal_stage(self) -> str: ...
    def relaunched_elsewhere(self, arguments: list[str], edited: str | None,
                             replaying: bool) -> None: ...


class Readings(Protocol):
    """What the link tells the inspector (inspector.py's Inspector)."""

    def show(self, event: Event) -> None: ...
    def detail_shown(self) -> None: ...


class OneSession(Protocol):
    """The app's session as the link reads it (session_view.py's SessionView)."""

    buffer: EventBuffer
    """Lines taken per drain tick at most: 10 ticks/s x 2500 is more than anyone reads;
    the rest is counted on screen and kept in the log files."""
    supervisor: LaunchPort | None
    own_relaunch: list[str] | None
    asked_to_stop: set[str]
    """The stops the operator asked for: their non-zero exit is not a failure."""

    def client(self) -> LaunchPort: ...
    def running(self) -> list[str]: ...
    def over_link(self) -> LaunchPort | None: ...
    def tell_shown(self) -> Coroutine[Any, Any, None] | None: ...
    def drain(self) -> Batch: ...


class SessionLink(App[int]):
    """The app's state and its link to the engine: the supervisor (in-process, or a session
    server's through RemoteSupervisor) runs on the engine thread; its events are drained on
    a timer into the tree, the output store and the status lines.

    The concerns of the app's keys are objects it holds, each over this class as its host:
    the keyboard, the inspector, navigation, quitting (`TuiLaunchApp` makes them and wires
    the widgets in `on_mount`)."""

    # held, not queried (set in on_mount): App.query_one searches the active screen, which
    # is a modal (help, quit) while the engine keeps reporting
    nodes: NodesTab
    launch_tree: LaunchTree
    output_panel: OutputPanel
    args_tab: ArgsTab
    tabs: TabbedContent
    status_bar: Static
    detail_bar: Static
    engine: EngineThread
    drain_timer: Timer
    keyboard: KeyboardNews
    view: OneSession
    buffer: EventBuffer
    asked_to_stop: set[str]
    inspector: Readings
    status: StatusWords

    def __init__(self, session: Session, log_dir: Path, scrollback: int = 5000,
                 sigterm_timeout: float = 5.0, sigkill_timeout: float = 5.0,
                 pane_fps: float = PANE_FPS, session_name: str = "",
                 owner: bool = False, keep_on_hangup: bool = False,
                 session_host: str | None = None,
                 remote_link: RemoteLink | None = None,
                 start_server: Callable[[], subprocess.Popen[bytes]] | None = None,
                 read_only: bool = False, port: LaunchPort | None = None) -> None:
        no_color = os.environ.get("NO_COLOR")
        super().__init__()
        # no animated tab underlines or scrolling: every frame is bytes over ssh
        self.animation_level = "none"
        if no_color is not None:
            # Textual takes NO_COLOR out of the environment; the nodes should still see it
            os.environ["NO_COLOR"] = no_color
        self.session = session
        self.log_dir = log_dir
        self.scrollback = scrollback
        # launch's defaults, for the processes whose file sets no timeout of their own
        self.sigterm_timeout = sigterm_timeout
        self.sigkill_timeout = sigkill_timeout
        self.pane_fps = pane_fps
        self.store = OutputStore(scrollback=scrollback, all_scrollback=scrollback * 4)
        # with a session name the launch runs in a session server and this app is a client
        self.session_name = session_name
        self.session_host = session_host  # the session runs there, reached over ssh
        self.given_port = port
        """A session's port handed in (an in-memory one, in tests/unit): followed as the
        session server's client would be, without opening one."""
        self.remote_link = remote_link  # an ssh link to it already open (attach made it)
        self.owner = owner
        self.keep_on_hangup = keep_on_hangup
        self.read_only = read_only
        """A view of a session that changes nothing (`--read-only`): its client refuses
        every change (client/read_only.py), and the refusal is shown as one line."""
        self.detached = False
        self.opened_at = time.time()
        """When this client opened: a relaunch before it is no news to it, also when its
        event comes after the history (the server's events at subscribing)."""
        self.exit_status = 0
        self.quitting = False
        self.terminal_lost = False
        self.signalled: str | None = None  # the signal that stopped the launch (SIGTERM)
        self.ended_elsewhere: str | None = None
        """Why the session ended when neither this client nor its terminal asked
        (`tuilaunch stop`, another client's quit): said on screen, then in the shell."""
        self.quit_started: float | None = None
        # the session's server not started yet: it is, once the tree is on screen (on_ready)
        self.starting = None if start_server is None else ServerStart(self, start_server)
        self.server_process: subprocess.Popen[bytes] | None = None
        self.start_error: str | None = None  # why the server did not start (said on exit)
        self.quit_before_start = False  # left before following the launch: it is stopped
        self.toasts = OnceToasts()
        self.topics_panel: TopicsPanel | None = None
        """The Topics tab's panel, once the tab was shown (tab_panels.py)."""

    def notify(self, message: str, *, title: str = "",
               severity: SeverityLevel = "information", timeout: float | None = None,
               markup: bool = True) -> None:
        """A toast, unless the same one is on screen (toasts.py)."""
        shown_for = self.NOTIFICATION_TIMEOUT if timeout is None else timeout
        if self.toasts.new(message, title, severity, shown_for):
            super().notify(message, title=title, severity=severity, timeout=timeout,
                           markup=markup)

    @on(Tree.NodeHighlighted, "#tree")
    def _selection_moved(self, event: Tree.NodeHighlighted[RowData]) -> None:
        """The Nodes tab showed the row (its pane, its detail): what follows the selection
        (the inspector's figures) and the keys that apply to it."""
        self.update_detail()
        if event.node.data is not None:
            self.refresh_bindings()  # the lifecycle keys apply to lifecycle nodes only

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        """A command a read-only client refused: said in one line (the commands' workers
        keep other failures to themselves, as the panels and the tree show them)."""
        error = event.worker.error
        if event.state == WorkerState.ERROR and isinstance(error, ReadOnlyError):
            self.notify(str(error), severity="warning")

    @work(group="supervisor", exit_on_error=False)
    async def run_supervisor(self) -> None:
        assert self.supervisor is not None
        self.exit_status = await self.engine.run(self.supervisor.run(keep_alive=True))
        if self.signalled is not None:
            self.exit_status = self.exit_status or 1
        self.drain()  # the last states and lines, then no more ticks during teardown
        self.drain_timer.stop()
        supervisor = self.supervisor
        if not (
                self.quitting or self.detached or supervisor.detached or supervisor.lost
                or supervisor.killed_server or self.terminal_lost):
            # the session ended and nobody here asked: say so before the screen goes
            self.ended_elsewhere = supervisor.shutdown_reason or "stopped"
            text = f"session {self.session_name} was stopped elsewhere " \
                   f"({self.ended_elsewhere}); leaving"
            self.status.drawn = text
            self.status_bar.update(Text(text, style="bold"))
            self.notify(text, title="session stopped", severity="warning")
            await asyncio.sleep(ENDED_ELSEWHERE_PAUSE)
        if self.terminal_lost:
            # Textual's teardown writes to the terminal and blocks forever on a hung-up one;
            # every process is stopped and every log closed, so leave now
            leave_now(self.exit_status)
        self.exit(self.exit_status)

    def refresh_bindings(self) -> None:
        # the engine's events keep coming while the app closes, and its screens may be gone
        # by then (a lifecycle node's last state as the launch stops, seen under load): the
        # footer they would refresh is gone with them
        try:
            super().refresh_bindings()
        except ScreenStackError:
            pass

    @property
    def supervisor(self) -> LaunchPort | None:
        """The session's port (its view's): None until the session is followed."""
        return self.view.supervisor

    async def show_typing_line(self, line: Widget) -> None:
        """The line taking the keys (`i`), above the Nodes tab's tree and pane."""
        await self.nodes.mount(line, before="#nodes-split")

    # --- engine events -------------------------------------------------------------------

    def drain(self) -> None:
        """The tick: the view shows what came (the tree, the pane), then the app acts on
        its news (`news_shown`), in the same call."""
        telling = self.view.tell_shown()  # over a link: the lines of the pane's process only
        if telling is not None:
            self.engine.submit(telling)  # asked again each tick until it is set
        self.news_shown(self.view.drain())

    def news_shown(self, shown: Batch, replaying: bool = False) -> None:
        """What the app does about a batch the view has shown: the readings a tab asked for
        to the inspector; for the rest, the status line, the keys that apply, the form
        after a relaunch. `replaying`: what happened before this client came, no news."""
        for reading in shown.readings:
            self.inspector.show(reading)
        self.nodes.batch_shown(shown, shown.news)
        if shown.readings:
            self.update_detail()  # a node's figures on its row, and so on the detail line
        for event in shown.relaunched:
            if event.lines != self.view.own_relaunch:
                self.status.relaunched_elsewhere(
                    event.lines, (event.data or {}).get("edited"),
                    replaying or event.time < self.opened_at)
            self.view.own_relaunch = None
        if shown.lifecycle or shown.news:
            # a start, an end, a state: the keys that apply to the selection may have
            # changed (Stop greyed once its node ended, Start offered); the footer greys or
            # offers its keys where they are, drawn anew only when other keys apply
            self.refresh_bindings()
        if shown.news or shown.lines:
            self.update_status()  # the batch's counts
            self.update_detail()
        else:
            if self.quit_started is not None or self.view.over_link() is not None:
                self.update_status()  # no batch: the signal stage, a link's silence move on
            # the selected row's words may change without a batch (the new plan a relaunch
            # fetched): drawn again only if they did, and not as a move of the selection,
            # which would restart the wait before its figures are asked for
            self.nodes.update_detail()

    def update_status(self) -> None:
        self.status.update()

    def update_detail(self) -> None:
        """The selected row in full on the Nodes tab's detail line; what follows the
        selection (the inspector's figures, the Topics tab's node) follows."""
        self.nodes.update_detail()
        self.inspector.detail_shown()
