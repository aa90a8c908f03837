"""Typing into a child's terminal: bytes written to its pseudo-terminal's master side.

The supervisor's event loop must never wait on a child: a node that does not read its stdin
fills the terminal's input queue, and then the master refuses more. What it refuses waits
here, in a bounded buffer, and is written when the loop says the terminal takes more; what
does not fit is dropped and counted, so the caller can say so.

A child whose terminal is not its controlling terminal (the fast vfork start, see
run/process/spawn.py) gets no signal from the kernel for a typed ctrl+c. The writer does what the
terminal would: while the terminal's settings have ISIG on (a line reader, a shell; tcgetattr
on the master reports the slave's settings on Linux), the INTR, QUIT and SUSP characters
(ctrl+c, ctrl+\\, ctrl+z by default) are SIGINT, SIGQUIT and SIGTSTP to the child's process
group, and what waited to be written is dropped, as a terminal flushes its input queue. With
ISIG off (a raw-key reader such as teleop_twist_keyboard) they are bytes like any other.
"""

from __future__ import annotations

import asyncio
import os
import signal
import termios

LIMIT = 64 * 1024
"""Bytes kept waiting for a child that does not read its terminal (a few screens of paste)."""


class InputRefused(Exception):
    """The process cannot be typed into: no terminal (output not shown), or it is closed."""


SIGNAL_KEYS = ((termios.VINTR, signal.SIGINT), (termios.VQUIT, signal.SIGQUIT),
               (termios.VSUSP, signal.SIGTSTP))
"""The terminal's special characters a terminal turns into signals while ISIG is on."""


class TerminalInput:
    """The writing side of one child's terminal (the master fd, owned by its reader)."""

    def __init__(self, fd: int, loop: asyncio.AbstractEventLoop | None = None,
                 pgid: int | None = None) -> None:
        self.fd = fd
        self.pgid = pgid
        """The process group to signal for a typed ctrl+c, ctrl+\\ or ctrl+z; None when the
        terminal is the child's controlling terminal (the kernel signals it then)."""
        self.signalled: list[signal.Signals] = []
        """Signals sent for keys typed, in order: a death by one is the operator's doing."""
        self.loop = loop
        """The loop that waits for the terminal to take more (the running one when None):
        `write` must be called on its thread."""
        self.pending = bytearray()
        self.dropped = 0
        """Bytes dropped so far because the child did not read them in time."""
        self.closed = False
        self._watching: asyncio.AbstractEventLoop | None = None

    def write(self, data: bytes) -> int:
        """Sends `data` to the child as typed keys; returns how many bytes were dropped
        (0 when all were written or queued). Never blocks."""
        if self.closed:
            raise InputRefused("its terminal is closed")
        keys = self._signal_keys() if self.pgid is not None else {}
        if not keys:
            return self._queue(data)
        before = self.dropped
        start = 0
        for index, byte in enumerate(data):
            sig = keys.get(byte)
            if sig is None:
                continue
            self._queue(data[start:index])
            self._signal(sig)
            start = index + 1
        self._queue(data[start:])
        return self.dropped - before

    def _signal_keys(self) -> dict[int, signal.Signals]:
        """The bytes that are signals now: none with ISIG off, or when settings are unknown."""
        try:
            attrs = termios.tcgetattr(self.fd)
        except (termios.error, OSError):
            return {}
        if not attrs[3] & termios.ISIG:
            return {}
        keys: dict[int, signal.Signals] = {}
        for index, sig in SIGNAL_KEYS:
            char = attrs[6][index]
            value = char[0] if isinstance(char, bytes) and char else char
            if isinstance(value, int) and value != 0:  # 0 (_POSIX_VDISABLE): turned off
                keys[value] = sig
        return keys

    def _signal(self, sig: signal.Signals) -> None:
        """A signal key: what waits is flushed, as a terminal flushes its input queue."""
        self.dropped += len(self.pending)
        self.pending.clear()
        self._unwatch()
        try:
            # on the master, TCOFLUSH drops what the child has not read yet: a partial line
            termios.tcflush(self.fd, termios.TCOFLUSH)
        except (termios.error, OSError):
            pass
        assert self.pgid is not None
        try:
            os.killpg(self.pgid, sig)
        except (ProcessLookupError, PermissionError):
            return  # gone meanwhile: its exit is on its way
        self.signalled.append(sig)

    def _queue(self, data: bytes) -> int:
        if not data:
            return 0
        if not self.pending:
            data = data[self._write_now(data):]
        room = max(LIMIT - len(self.pending), 0)
        dropped = max(len(data) - room, 0)
        self.pending += data[:room]
        self.dropped += dropped
        if self.pending:
            self._watch()
        return dropped

    def _write_now(self, data: bytes) -> int:
        written = 0
        while written < len(data):
            try:
                written += os.write(self.fd, data[written:])
            except (BlockingIOError, InterruptedError):
                break
            except OSError as exc:  # EIO: the child and its children are gone
                self.close()
                raise InputRefused(f"its terminal is closed ({exc.strerror})") from None
        return written

    def _watch(self) -> None:
        if self._watching is None:
            self._watching = self.loop or asyncio.get_running_loop()
            self._watching.add_writer(self.fd, self._writable)

    def _writable(self) -> None:
        try:
            sent = self._write_now(bytes(self.pending))
        except InputRefused:
            return  # closed: pending dropped by close()
        del self.pending[:sent]
        if not self.pending:
            self._unwatch()

    def _unwatch(self) -> None:
        if self._watching is not None:
            try:
                self._watching.remove_writer(self.fd)
            except (RuntimeError, ValueError, OSError):
                pass  # the loop is closed: nothing left to unregister
            self._watching = None

    def close(self) -> None:
        """Stops writing (before the fd is closed by its reader); what waits is dropped."""
        if self.closed:
            return
        self.closed = True
        self.dropped += len(self.pending)
        self.pending.clear()
        self._unwatch()
