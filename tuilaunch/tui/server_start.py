"""`tuilaunch FILE`: the session's server started once the TUI shows the tree, on a thread
of its own, and stopped at once when the TUI is left while it comes up.

What the command line reads once the TUI has ended stays on the app: the server's process
(`server_process`), why it did not start (`start_error`), whether the TUI was left before
following it (`quit_before_start`).
"""

from __future__ import annotations

import os
import subprocess
import threading
from collections.abc import Callable
from typing import Protocol

from textual.message import Message

from ..client.port import LaunchPort
from ..engine.errors import LaunchError
from ..engine.plan.resolve import remove_default_params_dir


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

    def post_message(self, message: Message) -> bool: ...


class ServerStart:
    """The server's start (`start`, once the tree is on screen) and its abandon (`abandon`,
    when the TUI is left meanwhile). `start_server` starts it and returns its process
    (LaunchError: why not); the app hears the outcome as a `ServerStarted` message."""

    def __init__(self, host: StartHost,
                 start_server: Callable[[], subprocess.Popen[bytes]]) -> None:
        self.host = host
        self.start_server = start_server
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
            host.post_message(ServerStarted(str(exc)))  # dropped if the app is gone
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
            server = host.server_process
            starting = self._thread is not None and server is None
        if server is not None:
            server.terminate()
        if host.terminal_lost and not starting:
            # Textual's teardown blocks on a dead terminal (as in run_supervisor), and
            # nothing is left to stop; else the starting thread leaves once it has
            leave_now(0)


def leave_now(status: int) -> None:
    """Ends the process at once (Textual's teardown would block on a hung-up terminal),
    leaving behind nothing atexit would have removed: the plan's parameter folder."""
    remove_default_params_dir()
    os._exit(status)
