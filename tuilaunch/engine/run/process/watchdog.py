"""Nothing of a launch survives its launcher, however the launcher dies.

A tiny process, started once per launch in its own session, holds the read end of a pipe
whose write end only the launcher holds. The launcher tells it each process group it creates
(`+pgid`) and each one that is gone (`-pgid`). When the pipe ends — a clean exit, a crash,
SIGKILL, an out-of-memory kill — the watchdog stops every process of the launch: the process
groups it was told about, and every process carrying the launch's mark in its environment
(grandchildren in their own groups or sessions: `timeout`, `setsid` daemons, `xterm -e`).
SIGTERM first, SIGKILL after a short grace.

This file runs as a script (`python -I -S watchdog.py TOKEN GRACE`): standard library only.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time

MARK = "TUILAUNCH_LAUNCH_ID"
"""Environment variable every process of a launch inherits: the launch tokens, `:`-joined
(a launch started by a launch carries both)."""


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
                [sys.executable, "-I", "-S", os.path.abspath(__file__), self.token,
                 str(self.grace)],
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
        import asyncio  # the launcher's side only: the watchdog process starts without it

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


# --- the watchdog process ----------------------------------------------------------------


def _launch_processes(token: str, groups: set[int]) -> list[int]:
    """Live processes in one of the groups or carrying the token in their environment."""
    found: list[int] = []
    me = os.getpid()
    needle = f"{MARK}=".encode()
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == me:
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as handle:
                fields = handle.read().rsplit(b")", 1)[1].split()
            if fields[0] == b"Z":
                continue
            if int(fields[2]) in groups:
                found.append(int(entry))
                continue
            with open(f"/proc/{entry}/environ", "rb") as handle:
                environ = handle.read()
        except (OSError, IndexError, ValueError):
            continue  # gone meanwhile, or not ours to read
        for item in environ.split(b"\0"):
            if item.startswith(needle) and token.encode() in item[len(needle):].split(b":"):
                found.append(int(entry))
                break
    return found


def sweep(token: str, groups: set[int], grace: float) -> None:
    for sig, wait in ((signal.SIGTERM, grace), (signal.SIGKILL, 2.0)):
        targets = _launch_processes(token, groups)
        if not targets:
            return
        for pid in targets:
            try:
                os.kill(pid, sig)
            except OSError:
                pass
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline:
            time.sleep(0.02)
            remaining = _launch_processes(token, groups)
            if not remaining:
                return
            for pid in remaining:  # late forks of a dying process get the same signal
                if pid not in targets:
                    targets.append(pid)
                    try:
                        os.kill(pid, sig)
                    except OSError:
                        pass


def main(argv: list[str]) -> None:
    token, grace = argv[1], float(argv[2])
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGPIPE):
        signal.signal(sig, signal.SIG_IGN)  # a terminal's Ctrl+C or hang-up is not for us
    groups: set[int] = set()
    pending = b""
    while True:
        try:
            chunk = os.read(0, 4096)
        except InterruptedError:
            continue
        except OSError:
            break
        if not chunk:
            break
        *lines, pending = (pending + chunk).split(b"\n")
        for line in lines:
            if line[:1] == b"+":
                groups.add(int(line[1:]))
            elif line[:1] == b"-":
                groups.discard(int(line[1:]))
    sweep(token, groups, grace)


if __name__ == "__main__":
    main(sys.argv)
