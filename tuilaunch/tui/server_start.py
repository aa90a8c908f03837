"""`tuilaunch FILE`: the session's server, started before the TUI (it loads the launch file
while the TUI imports), waited for on a thread of its own, and stopped at once when the
TUI is left while it comes up. The TUI draws the plan the server sends, then says so
(`plan_shown`): the server's first process starts then, so the tree is on screen first.

What the command line reads once the TUI has ended stays on the app: the server's process
(`server_process`), why it did not start (`start_error`), whether the TUI was left before
following it (`quit_before_start`).
"""

from __future__ import annotations

import os
import subprocess
import threading
from collections.abc import Callable
from concurrent.futures import Future
from typing import Any, Protocol

from textual.message import Message
from textual.screen import Screen
from textual.widget import Widget
from textual.widgets import Tree

from ..client.port import LaunchPort
from ..client.session_start import StartingServer
from ..engine.errors import LaunchError
from ..engine.plan.resolve import remove_default_params_dir
from ..engine.run.engine_thread import EngineThread
from ..engine.run.vocabulary.requests import PlanShown

SHOWN_TRIES = 50
"""Refreshes `plan_shown` waits at most for the tree to have drawn its rows."""


class ServerStarted(Message):
    """The session's server answers (`error` None), or could not start (why)."""

    def __init__(self, error: str | None) -> None:
        super().__init__()
        self.error = error


class StartHost(Protocol):
    """The app, as its server's start sees it."""

    server_process: subprocess.Popen[bytes] | None
    quit_before_start: bool
    terminal_lost: bool
    @property
    def supervisor(self) -> LaunchPort | None:
        """The session's client, once it is followed."""

    engine: EngineThread

    @property
    def launch_tree(self) -> Tree[Any]: ...

    @property
    def screen(self) -> Screen[Any]: ...

    def call_after_refresh(self, callback: Callable[..., object], *args: Any) -> bool: ...

    def post_message(self, message: Message) -> bool: ...


class ServerStart:
    """The server's start (`start`, once the TUI is on screen) and its abandon (`abandon`,
    when the TUI is left meanwhile). `start_server` returns the server's process once it
    answers (LaunchError: why not): a `StartingServer`, already started, is waited for;
    the app hears the outcome as a `ServerStarted` message, and says `plan_shown` once it
    has drawn the plan."""

    def __init__(self, host: StartHost,
                 start_server: Callable[[], subprocess.Popen[bytes]]) -> None:
        self.host = host
        self.start_server = start_server
        self.spawned = start_server.process if isinstance(start_server, StartingServer) \
            else None
        """The server started before the TUI: stopped with it even before it answers."""
        self._lock = threading.Lock()  # the server comes up while the app may leave
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        """Starts the session's server, and so the launch, then follows it as a client.

        On a thread of its own, not a worker: a quit while the server comes up must not wait
        for it, and the thread, not killed at exit, still stops what it started."""
        with self._lock:
            if self.host.quit_before_start:
                return
            self._thread = threading.Thread(target=self._start_server, name="session-start")
            self._thread.start()

    def _start_server(self) -> None:
        host = self.host
        try:
            server = self.start_server()
        except LaunchError as exc:
            with self._lock:
                abandoned = host.quit_before_start
            if not abandoned:  # else it ended because it was stopped: no error of its own
                host.post_message(ServerStarted(str(exc)))  # dropped if the app is gone
            elif host.terminal_lost:
                leave_now(0)
            return
        with self._lock:
            host.server_process = server
            abandoned = host.quit_before_start
        if abandoned:  # the app was left while the server came up: the launch stops at once
            server.terminate()
            if host.terminal_lost:  # the UI is stuck on the dead terminal (abandon)
                server.wait()
                leave_now(0)
            return
        host.post_message(ServerStarted(None))

    def abandon(self) -> None:
        """Leaving before the launch is followed (q, SIGHUP or SIGTERM while its server comes
        up): the server is stopped as soon as it is up, and with it what it started."""
        host = self.host
        if host.supervisor is not None:
            return
        with self._lock:
            host.quit_before_start = True
            server = host.server_process or self.spawned
            # its thread ends once the server has (stopped here), and leaves then
            starting = self._thread is not None and host.server_process is None
        if server is not None:
            server.terminate()
        if host.terminal_lost and not starting:
            # Textual's teardown blocks on a dead terminal (as in run_supervisor), and
            # nothing is left to stop; else the starting thread leaves once it has
            leave_now(0)


    def plan_shown(self, tries: int = 0, settled: bool = False) -> None:
        """The plan the server sent is on screen: its launch's first process may start.

        Called after a refresh, but the tree lays its rows out on its own idle, which can
        come after the screen's, and then asks the screen to paint them: asked again after
        each refresh until the tree has nothing left to lay out, then once more, so the
        screen has painted what the tree last asked for (`SHOWN_TRIES` refreshes at most:
        the server's own wait is the backstop)."""
        host = self.host
        if host.supervisor is None or host.quit_before_start:
            return
        tree = host.launch_tree
        pending = _unpainted(tree) or _unpainted(host.screen) or \
            bool(getattr(host, "_batch_count", 0)) or \
            tree.virtual_size.height != tree.last_line + 1  # last_line builds its rows
        if (pending or not settled) and tries < SHOWN_TRIES:
            host.call_after_refresh(self.plan_shown, tries + 1, not pending)
            return
        # not awaited: the server starts the launch after its OWNER_WAIT anyway
        host.engine.submit(host.supervisor.request(PlanShown())).add_done_callback(
            _ignored)


def _unpainted(widget: Widget) -> bool:
    """Whether the tree, or the screen, holds changes not yet written to the terminal: a
    screen idles and calls back after a refresh that painted nothing while it still holds
    widgets to paint, or while the app batches its updates (a loaded machine showed the
    rows first as running, 1 launch in 12)."""
    return bool(getattr(widget, "_layout_required", False) or
                getattr(widget, "_repaint_required", False) or
                getattr(widget, "_dirty_widgets", None))


def _ignored(future: Future[Any]) -> None:
    future.exception()  # a link gone meanwhile: the server's own wait starts the launch


def leave_now(status: int) -> None:
    """Ends the process at once (Textual's teardown would block on a hung-up terminal),
    leaving behind nothing atexit would have removed: the plan's parameter folder."""
    remove_default_params_dir()
    os._exit(status)
