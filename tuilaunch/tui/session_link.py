"""The app's state and its link to the engine: supervisor wiring, engine events, status.

Engine events reach the UI through one EventBuffer drained on a timer, so a flood from a
node costs one batched write per pane per tick: each tick's batch goes to the Nodes tab as
a message (nodes/tab.py), the readings a tab asked for to the inspector. The App
constructor does no I/O: the session's client starts in on_mount.
"""

from __future__ import annotations

import asyncio
import os
import subprocess
import threading
import time
from collections.abc import Callable
from pathlib import Path

from rich.text import Text
from textual import on, work
from textual.app import App, ScreenStackError
from textual.message import Message
from textual.timer import Timer
from textual.widgets import Static, TabbedContent, Tree
from textual.worker import Worker, WorkerState

from ..client.link import lost_link_line
from ..client.port import LaunchPort
from ..client.read_only import ReadOnlyError
from ..engine.errors import LaunchError
from ..engine.plan.resolve import remove_default_params_dir
from ..engine.plan.session import Session
from ..engine.run.engine_thread import EngineThread
from ..engine.run.event_buffer import EventBuffer
from ..engine.run.events import LIVE_STATES, Event, Reading
from ..engine.run.machines.remote import RemoteLink
from ..engine.run.session.session_dir import SessionError
from .arguments import ArgsTab
from .nodes.tab import NodesTab, SessionEvents
from .output_store import WARN, Line, OutputStore
from .screens.output_panel import OutputPanel
from .screens.tree_panel import LaunchTree, RowData

# the UI's tick: events are taken from the engine this often; the output pane repaints at
# most PANE_FPS times a second and only when what it shows changed, so a terminal over ssh
# gets little more than what changed on screen
DRAIN_HZ = 10
PANE_FPS = 1.0
PANE_CHROME = 6
"""Rows of the screen that are not the output pane (status, tabs, detail, the pane's own
status line, footer): a display over a link is sent a pane's worth of lines a second, as
the pane repaints once a second and shows no more."""
SILENCE_SHOWN = 5.0
"""Seconds without a word from the other side of a link (probed meanwhile) after which the
status line says how long: a hung link says nothing else for ssh's 15 s."""
ENDED_ELSEWHERE_PAUSE = 3.0
"""Seconds a client shows that its session was stopped elsewhere before it leaves."""
WARNINGS_SHOWN = 3
"""The plan's warnings shown as toasts when the TUI opens; all are in the all nodes pane."""


class ServerStarted(Message):
    """The session's server answers (`error` None), or could not start (why)."""

    def __init__(self, error: str | None) -> None:
        super().__init__()
        self.error = error


class SessionLink(App[int]):
    """The app's state and its link to the engine: the supervisor (in-process, or a session
    server's through RemoteSupervisor) runs on the engine thread; its events are drained on
    a timer into the tree, the output store and the status lines.

    The concerns built on it (node commands, navigation, arguments, quitting) are mixins of
    this class; `TuiLaunchApp` composes them and wires the widgets in `on_mount`."""

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
        # lines taken per drain tick at most: 10 ticks/s x 2500 is more than anyone reads;
        # the rest is counted on screen and kept in the log files
        self.buffer = EventBuffer(max_lines=2500)
        self.supervisor: LaunchPort | None = None
        self.given_port = port
        """A session's port handed in (an in-memory one, in tests/unit): followed as the
        session server's client would be, without opening one."""
        # with a session name the launch runs in a session server and this app is a client
        self.session_name = session_name
        self.session_host = session_host  # the session runs there, reached over ssh
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
        self.own_relaunch: list[str] | None = None
        self.exit_status = 0
        self.quitting = False
        self.terminal_lost = False
        self.signalled: str | None = None  # the signal that stopped the launch (SIGTERM)
        self.ended_elsewhere: str | None = None
        """Why the session ended when neither this client nor its terminal asked
        (`tuilaunch stop`, another client's quit): said on screen, then in the shell."""
        # stops the operator asked for: their non-zero exit is not a failure
        self.asked_to_stop: set[str] = set()
        self.quit_started: float | None = None
        self._status_text = ""
        # the session's server not started yet: it is, once the tree is on screen (on_ready)
        self.start_server = start_server
        self.server_process: subprocess.Popen[bytes] | None = None
        self.start_error: str | None = None  # why the server did not start (said on exit)
        self._start_lock = threading.Lock()  # the server comes up while the app may leave
        self._start_thread: threading.Thread | None = None
        self.quit_before_start = False  # left before following the launch: it is stopped

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
            self._status_text = text
            self.status_bar.update(Text(text, style="bold"))
            self.notify(text, title="session stopped", severity="warning")
            await asyncio.sleep(ENDED_ELSEWHERE_PAUSE)
        if self.terminal_lost:
            # Textual's teardown writes to the terminal and blocks forever on a hung-up one;
            # every process is stopped and every log closed, so leave now
            leave_now(self.exit_status)
        self.exit(self.exit_status)

    def start_launch(self) -> None:
        """Starts the session's server, and so the launch, then follows it as a client.

        On a thread of its own, not a worker: a quit while the server comes up must not wait
        for it, and the thread, not killed at exit, still stops what it started."""
        with self._start_lock:
            if self.quit_before_start:
                return
            self._start_thread = threading.Thread(target=self._start_server,
                                                  name="session-start")
            self._start_thread.start()

    def _start_server(self) -> None:
        assert self.start_server is not None
        try:
            server = self.start_server()
        except LaunchError as exc:
            self.post_message(ServerStarted(str(exc)))  # dropped if the app is gone
            return
        with self._start_lock:
            self.server_process = server
            abandoned = self.quit_before_start
        if abandoned:  # the app was left while the server came up: the launch stops at once
            server.terminate()
            if self.terminal_lost:  # the UI is stuck on the dead terminal (abandon_start)
                server.wait()
                leave_now(0)
            return
        self.post_message(ServerStarted(None))

    def on_server_started(self, message: ServerStarted) -> None:
        if message.error is not None:
            self.start_error = message.error
            self.exit(2, return_code=2)
        elif not self.quit_before_start:
            self.wire_supervisor()

    def abandon_start(self) -> None:
        """Leaving before the launch is followed (q, SIGHUP or SIGTERM while its server comes
        up): the server is stopped as soon as it is up, and with it what it started."""
        if self.supervisor is not None or self.start_server is None:
            return
        with self._start_lock:
            self.quit_before_start = True
            server = self.server_process
            starting = self._start_thread is not None and server is None
        if server is not None:
            server.terminate()
        if self.terminal_lost and not starting:
            # Textual's teardown blocks on a dead terminal (as in run_supervisor), and
            # nothing is left to stop; else the starting thread leaves once it has
            leave_now(0)

    def wire_supervisor(self) -> None:
        """Connects the panels to the supervisor (the app's on_mount)."""
        raise NotImplementedError

    def refresh_bindings(self) -> None:
        # the engine's events keep coming while the app closes, and its screens may be gone
        # by then (a lifecycle node's last state as the launch stops, seen under load): the
        # footer they would refresh is gone with them
        try:
            super().refresh_bindings()
        except ScreenStackError:
            pass

    def on_unmount(self) -> None:
        self.abandon_start()
        # any exit path that skipped the graceful shutdown still leaves no process behind
        if self.supervisor is not None:
            self.kill_all()
            self.engine.stop()

    def kill_all(self) -> None:
        """SIGKILL what is left, on the engine's thread: the supervisor (its process table,
        its watchdog pipe) belongs to that thread while its loop runs."""
        assert self.supervisor is not None
        if self.engine.loop.is_running():
            try:
                self.engine.call(self.supervisor.kill_all)
                return
            except Exception:
                pass  # the loop ended meanwhile: nothing runs there any more
        self.supervisor.kill_all()

    def client(self) -> LaunchPort:
        """The session's client; SessionError (a LaunchError) before the session is
        followed (a key pressed, a tab shown, while its server still comes up)."""
        if self.supervisor is None:
            raise SessionError(f"session {self.session_name} is not followed yet")
        return self.supervisor

    def selected_process(self) -> str | None:
        """The process of the Nodes tab's selected row (None: a group, the root)."""
        return self.nodes.selected_process()

    def running(self) -> list[str]:
        if self.supervisor is None:
            return []
        return [p for p, s in self.supervisor.states.items() if s in LIVE_STATES]

    # --- engine events -------------------------------------------------------------------

    def drain(self) -> None:
        self.show_events(self.buffer.drain())

    def show_events(self, events: list[Event], replaying: bool = False) -> None:
        """A batch of the session's events (the tick's, often none): the readings a tab
        asked for to the inspector; the rest down to the Nodes tab, by message, which says
        when they are on screen (`on_nodes_tab_shown`). `replaying`: what happened before
        this client came, shown but no news, at once."""
        self._tell_pane_shown()
        rest = [event for event in events if not isinstance(event, Reading)]
        readings = [event for event in events if isinstance(event, Reading)]
        for reading in readings:
            self.inspector_event(reading)
        if readings:
            self.update_detail()  # a node's figures on its row, and so on the detail line
        if replaying:
            # shown with the tree it comes with (the states the session has now), before
            # either is on screen: no frame has a row's end without its lines
            self.nodes.show_batch(rest, replaying=True)
        else:
            self.nodes.post_message(SessionEvents(rest))
        if not rest and (self.quit_started is not None or self.over_link() is not None):
            self.update_status()  # the signal stage, a link's silence: move on with time

    def on_nodes_tab_shown(self, message: NodesTab.Shown) -> None:
        """The Nodes tab shows a batch: the status line, the keys that apply, the form
        after a relaunch, follow."""
        for event in message.shown.relaunched:
            if event.lines != self.own_relaunch:
                self._relaunched_elsewhere(event.lines, (event.data or {}).get("edited"),
                                           message.replaying or event.time < self.opened_at)
            self.own_relaunch = None
        if message.shown.lifecycle:
            self.refresh_bindings()
        self.update_status()
        self.update_detail()

    def _tell_pane_shown(self) -> None:
        """Over an ssh link the server sends only the output pane's process's lines (all
        for the all-nodes pane); the others' are read from their log files when shown."""
        supervisor = self.over_link()
        if supervisor is None:
            return
        shown = self.output_panel.view.process
        if shown != supervisor.only:  # set on the engine thread: asked again until it is
            self.engine.submit(supervisor.show(shown))

    def pane_save_dir(self) -> Path:
        """Where `w` writes a pane: the launch's log folder, which is on this computer,
        unless the session runs on another machine (its log folder is there; a pane is
        saved here, in a folder named after that machine and session)."""
        if self.session_host is None:
            return self.log_dir
        base = os.environ.get("ROS_LOG_DIR") or os.path.join(
            os.environ.get("ROS_HOME") or os.path.expanduser("~/.ros"), "log")
        return Path(base) / f"tuilaunch-{self.session_host}-{self.session_name}"

    def over_link(self) -> LaunchPort | None:
        """The session's supervisor when an ssh link is between (the session is on another
        machine): what crosses it is then kept to what the screen shows."""
        supervisor = self.supervisor
        return supervisor if supervisor is not None and supervisor.host is not None else None

    def inspector_event(self, event: Event) -> None:
        """A `rates`, `echo` or `resources` event (the Inspector mixin shows them)."""

    def tab_shown(self, pane: str) -> None:
        """A tab came on screen (the Inspector mixin measures only what it shows)."""

    def _relaunched_elsewhere(self, arguments: list[str], edited: str | None,
                              replaying: bool) -> None:
        """Another operator applied new values, or an edited file (`edited`: which one):
        the form shows them, so an edit here starts from what runs, never silently reverts
        theirs."""
        self.args_tab.show_form()
        if not replaying:  # a relaunch before this client came is no news to it
            what = [f"{edited} changed"] if edited else []
            what += [" ".join(arguments)] if arguments else [] if edited else ["defaults"]
            self.notify(f"relaunched by another client: {'; '.join(what)}")
        self.refresh_bindings()

    def say_plan_warnings(self) -> None:
        """What the plan warns about (a mistyped argument, a missing parameter file), said
        in the TUI: printed before it took the screen, it would only be seen after quitting."""
        lines: list[Line] = []
        warnings = self.session.plan.warnings
        for warning in warnings:
            lines += self.store.add_event("launch", f"warning: {warning}", WARN)
        # to the operator who gave the values (an attached client finds them in the all
        # nodes pane, as `launch` lines);
        # a few at most: a column of toasts would hide the screen
        if self.owner:
            for warning in warnings[:WARNINGS_SHOWN]:
                self.notify(warning, title="warning", severity="warning", timeout=20)
            if len(warnings) > WARNINGS_SHOWN:
                self.notify(f"{len(warnings) - WARNINGS_SHOWN} more warnings: in the all "
                            "nodes pane (a)", severity="warning", timeout=20)
        if lines:
            self.nodes.show_lines(lines)

    def update_status(self) -> None:
        if self.supervisor is None or self.ended_elsewhere is not None:
            return  # the line says the session ended elsewhere until the TUI leaves
        counts: dict[str, int] = {}
        shown = self.launch_tree.states
        for proc in self.session.plan.processes:
            state = shown.get(proc.id) or self.supervisor.states.get(proc.id, "pending")
            counts[state] = counts.get(state, 0) + 1
        order = ("running", "unknown", "pending", "stopping", "exited", "failed", "respawning",
                 "skipped")  # unknown: placed on a machine whose link is lost
        text = "  ".join(f"{counts[s]} {'waiting' if s == 'pending' else s}" for s in order
                         if counts.get(s))
        undeclared = self.session.undeclared()
        args = " ".join(f"{k}:={v}" for k, v in self.session.arguments.items()
                        if k not in undeclared)
        if undeclared:  # a typo applies nothing: said first (a narrow header cuts the
            # end), never listed with what applies
            args = f"not declared: {', '.join(undeclared)}  {args}"
        prefix = ""
        if self.quitting:
            still = self.running()
            prefix = f"stopping {', '.join(still)} ({self.signal_stage()})... " if still \
                else "stopped. "
        name = Path(self.session.plan.file).name
        where = f"{self.session_host}:" if self.session_host else ""
        name = f"[{where}{self.session_name}{' read-only' if self.read_only else ''}] {name}"
        link = self.over_link()
        if link is not None and link.link_lost:
            # what is shown is as it was when the link dropped; the short form first, so
            # 80 columns show it whole, then the reason (the latest attempt's), its end
            # kept; an attempt under way says so, and how long it has taken
            since = link.attempt_since
            prefix = lost_link_line(
                link.host or "", self.session_name, link.lost_reason or "", link.attempt,
                None if since is None else time.monotonic() - since,
                self.status_bar.size.width or 78) + f"  {prefix}"
            name = Path(self.session.plan.file).name
        elif link is not None and link.silent_for() >= SILENCE_SHOWN:
            prefix = f"no word from {link.host} for {link.silent_for():.0f} s · {prefix}"
        line = f"{prefix}{name}  {text}  {args}"
        if line != self._status_text:  # an unchanged line is not sent to the terminal again
            self._status_text = line
            # cut with an ellipsis where it does not fit: something is left out, and seen so
            self.status_bar.update(Text(line, no_wrap=True, overflow="ellipsis"))

    def signal_stage(self) -> str:
        """Where the SIGINT -> SIGTERM -> SIGKILL escalation is, from the timeouts of the
        processes still running (the file's or `sigterm_timeout:=`, else launch's 5 s: the
        server waits as long)."""
        if self.quit_started is None:
            return "SIGINT sent"
        sigterm, sigkill = self._escalation()
        elapsed = time.monotonic() - self.quit_started
        if elapsed < sigterm:
            return f"SIGINT sent, SIGTERM in {sigterm - elapsed:.0f} s; q: kill now"
        elapsed -= sigterm
        if elapsed < sigkill:
            return f"SIGTERM sent, SIGKILL in {sigkill - elapsed:.0f} s; q: kill now"
        return "SIGKILL sent"

    def _escalation(self) -> tuple[float, float]:
        still = set(self.running())
        waits = [(self.sigterm_timeout if p.sigterm_timeout is None else p.sigterm_timeout,
                  self.sigkill_timeout if p.sigkill_timeout is None else p.sigkill_timeout)
                 for p in self.session.plan.processes if p.id in still]
        return (max(w[0] for w in waits), max(w[1] for w in waits)) if waits else \
            (self.sigterm_timeout, self.sigkill_timeout)

    def update_detail(self) -> None:
        """The selected row in full on the Nodes tab's detail line."""
        self.nodes.update_detail()

    def describe_waiting(self) -> None:
        """Each process not started yet says why on its row."""
        self.nodes.events.describe_waiting()


def leave_now(status: int) -> None:
    """Ends the process at once (Textual's teardown would block on a hung-up terminal),
    leaving behind nothing atexit would have removed: the plan's parameter folder."""
    remove_default_params_dir()
    os._exit(status)
