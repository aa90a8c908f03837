"""Typing into a child's terminal: bytes written to its pseudo-terminal's master side.

The supervisor's event loop must never wait on a child: a node that does not read its stdin
fills the terminal's input queue, and then the master refuses more. What it refuses waits
here, in a bounded buffer, and is written when the loop says the terminal takes more; what
does not fit is dropped and counted, so the caller can say so.
"""

from __future__ import annotations

import asyncio
import os

LIMIT = 64 * 1024
"""Bytes kept waiting for a child that does not read its terminal (a few screens of paste)."""


class InputRefused(Exception):
    """The process cannot be typed into: no terminal (output not shown), or it is closed."""


class TerminalInput:
    """The writing side of one child's terminal (the master fd, owned by its reader)."""

    def __init__(self, fd: int, loop: asyncio.AbstractEventLoop | None = None) -> None:
        self.fd = fd
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
