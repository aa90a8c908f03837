"""Nothing of a launch survives its launcher, however the launcher dies: the launcher's side.

A tiny process (watchdog_process.py), started once per launch in its own session, holds the
read end of a pipe whose write end only the launcher holds. The launcher tells it each
process group it creates (`+pgid`) and each one that is gone (`-pgid`). When the pipe ends —
a clean exit, a crash, SIGKILL, an out-of-memory kill — the watchdog stops every process of
the launch: the process groups it was told about, and every process carrying the launch's
mark in its environment (grandchildren in their own groups or sessions: `timeout`, `setsid`
daemons, `xterm -e`). SIGTERM first, SIGKILL after a short grace.
"""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
import threading

from . import watchdog_process
from .watchdog_process import MARK


class Watchdog:
    """The launcher's side. Started on first use; `close` ends it, which sweeps stragglers."""

    def __init__(self, grace: float = 1.0) -> None:
        self.token = f"{os.getpid()}-{os.urandom(6).hex()}"
        self.grace = grace
        self.error: str | None = None
        self._process: subprocess.Popen[bytes] | None = None
        self._fd: int | None = None
        self._pending: list[str] = []
        # the UI thread may end the launch (kill_all) while the engine thread writes: one
        # writer at a time, and the pipe is closed exactly once (a second close could hit
        # a descriptor the number was given to meanwhile)
        self._lock = threading.Lock()

    def mark(self, env: dict[str, str]) -> None:
        """Marks a child's environment as part of this launch."""
        outer = env.get(MARK)
        env[MARK] = f"{outer}:{self.token}" if outer else self.token

    def start(self) -> None:
        if self._process is not None or self.error is not None:
            return
        read_end, write_end = os.pipe()
        try:
            self._process = subprocess.Popen(
                [sys.executable, "-I", "-S", os.path.abspath(watchdog_process.__file__),
                 self.token, str(self.grace)],
                stdin=read_end, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                start_new_session=True, cwd="/")
        except OSError as exc:
            os.close(write_end)
            self.error = f"cannot start the watchdog: {exc.strerror or exc}"
            return
        finally:
            os.close(read_end)
        os.set_blocking(write_end, False)
        self._fd = write_end

    def watch(self, pgid: int) -> None:
        self._send(f"+{pgid}\n")

    def forget(self, pgid: int) -> None:
        self._send(f"-{pgid}\n")

    def _send(self, text: str) -> None:
        """Queued and written once per event-loop turn: a write per process group would
        wake the watchdog a hundred times while a hundred processes start. A process
        started just before tuilaunch dies is still found by its mark."""
        with self._lock:
            if self._fd is None:
                return
            self._pending.append(text)
            if len(self._pending) > 1:
                return  # a flush is already due
        try:
            asyncio.get_running_loop().call_soon(self.flush)
        except RuntimeError:
            self.flush()  # no event loop here: at once

    def flush(self) -> None:
        with self._lock:
            self._flush_locked()

    def _flush_locked(self) -> None:
        data, self._pending = "".join(self._pending), []
        if self._fd is None or not data:
            return
        try:
            os.write(self._fd, data.encode())
        except OSError as exc:
            self.error = f"the watchdog stopped listening: {exc.strerror or exc}"
            self._close_pipe_locked()

    def _close_pipe_locked(self) -> None:
        fd, self._fd = self._fd, None
        if fd is not None:
            os.close(fd)

    def close(self) -> None:
        """Ends the watchdog: it stops whatever of the launch is still there, then exits."""
        with self._lock:
            self._flush_locked()
            self._close_pipe_locked()

    def finished(self) -> bool:
        return self._process is None or self._process.poll() is not None

    @property
    def pid(self) -> int | None:
        return self._process.pid if self._process is not None else None


__all__ = ["MARK", "Watchdog"]
