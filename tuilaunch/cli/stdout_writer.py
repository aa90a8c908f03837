"""A writer for headless output that never blocks the launch.

Writing straight to stdout from the event loop ties every node to its reader: a terminal
paused with Ctrl+S, an ssh link slower than the output, or `| less` left open fill the
pipe, the loop blocks in `write`, the nodes' own pipes are no longer read, and the nodes
freeze writing their output (Ctrl+C is not even seen). Here the loop only appends to a
queue; one thread writes it to the file descriptor. Lines are skipped only when the reader
does not keep up: a write has waited on it for STALL with QUEUE_LIMIT queued, or
HARD_LIMIT is queued. A regular file or a pipe whose reader keeps up gets every line, even
when the writer thread lags behind a flood for want of CPU. Skipped lines are counted: the
log files hold every line, and a notice says how many were skipped once the reader catches
up. Lines about processes (started, exited, failed) are always queued.
"""

from __future__ import annotations

import os
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import TextIO

from ..engine.run.session.launch_prints import PrintedLines

QUEUE_LIMIT = 1 << 20
"""Bytes of output waiting for a slow reader before lines are skipped: a second of a busy
robot's output, far more than a terminal that keeps up ever has waiting."""
STALL = 0.1
"""Seconds a write of one CHUNK may wait on the reader before it counts as one that does
not keep up (a terminal paused with Ctrl+S, an ssh link slower than the output); a reader
that keeps up takes a chunk in well under a millisecond."""
CHUNK = 64 << 10
"""Bytes per write: a pipe's buffer, so each write's wait says how fast the reader is."""
HARD_LIMIT = 64 << 20
"""Bytes queued past which lines are skipped whatever the reader: memory stays bounded
when a reader takes its output steadily but slower than a flood."""

GATHER = 0.003
"""Seconds the writer lets output gather after it wakes: under a flood it then wakes a few
hundred times a second for large writes, not once per block of lines (each wake-up takes
the interpreter's lock from the loop that reads the nodes); a line still shows at once to
the eye."""
GATHER_BELOW = 64 << 10
"""Bytes queued under which the writer lets more gather; past it, it writes at once."""

EXIT_PATIENCE = 5.0
"""At exit, how long to wait for a reader that takes nothing before leaving the rest."""


class BackgroundWriter:
    def __init__(self, fd: int, encoding: str, on_error: Callable[[OSError], None],
                 skipped_notice: Callable[[int], str], limit: int = QUEUE_LIMIT) -> None:
        self.fd = fd
        self.encoding = encoding
        self.limit = limit
        self.written = 0  # bytes the reader has taken, for `close` to see progress
        self._on_error = on_error
        self._notice = skipped_notice
        self._queue: deque[str] = deque()
        self._queued = 0
        self._skipped = 0
        self._closed = False
        self._failed = False
        self._waiting_since: float | None = None  # when the write in progress began
        self._ready = threading.Condition()
        self._thread = threading.Thread(target=self._run, name="stdout", daemon=True)
        self._thread.start()

    def write(self, text: str, lines: int = 0) -> None:
        """Queues `text`; with `lines` (output lines), it may be skipped when the reader is
        too far behind."""
        with self._ready:
            if self._failed or self._closed:
                return
            if lines and self._queued + len(text) > self.limit and self._behind():
                self._skipped += lines
                return
            self._queue.append(text)
            self._queued += len(text)
            self._ready.notify()

    def _behind(self) -> bool:
        """The reader does not keep up: a write waits on it, or far too much is queued.
        A queue that grew while the writer only waited for CPU (a flood into a file) is
        written whole."""
        since = self._waiting_since
        return self._queued > HARD_LIMIT or (
            since is not None and time.monotonic() - since > STALL)

    def close(self, patience: float = EXIT_PATIENCE) -> None:
        """Writes what is queued, waiting as long as the reader takes something at least
        every `patience` seconds; a reader that takes nothing is left behind."""
        with self._ready:
            self._closed = True
            self._ready.notify()
        seen, deadline = self.written, time.monotonic() + patience
        while self._thread.is_alive():
            self._thread.join(0.05)
            if self.written != seen:
                seen, deadline = self.written, time.monotonic() + patience
            elif time.monotonic() > deadline:
                return  # a daemon thread: it cannot keep the process alive

    def _run(self) -> None:
        while True:
            with self._ready:
                while not self._queue and not self._skipped and not self._closed:
                    self._ready.wait()
                # only while little waits: a reader that lags gets the rest at once
                gather = not self._closed and self._queued < GATHER_BELOW
            if gather:
                time.sleep(GATHER)
            with self._ready:
                if not self._queue and not self._skipped:
                    return  # closed, and all written
                text = "".join(self._queue)
                self._queue.clear()
                self._queued = 0
                skipped, self._skipped = self._skipped, 0
            if skipped:
                text += self._notice(skipped)
            try:
                self._write_all(text.encode(self.encoding, "backslashreplace"))
            except OSError as exc:
                with self._ready:
                    self._failed = True
                    self._queue.clear()
                self._on_error(exc)
                return

    def _write_all(self, data: bytes) -> None:
        view = memoryview(data)
        try:
            while view:
                self._waiting_since = time.monotonic()
                done = os.write(self.fd, view[:CHUNK])  # blocks this thread only
                view = view[done:]
                self.written += done
        finally:
            self._waiting_since = None


class LineJoiner(PrintedLines):
    """`sys.stdout` while a BackgroundWriter owns the stream: what launch-file code prints at
    run time (an OpaqueFunction, an event handler's callback) joins the writer's queue a
    whole line at a time. Printed straight to the file descriptor, it could be cut by the
    writer thread's lines: with PYTHONUNBUFFERED (usual in ROS containers) `print(a, b)`
    writes each piece apart. Queued, it also keeps its place among the launch's lines."""

    def __init__(self, writer: BackgroundWriter, original: TextIO) -> None:
        super().__init__(original)
        self._writer = writer

    def _whole(self, block: str) -> None:
        self._writer.write(block)

    def flush(self) -> None:
        # a line left open on purpose (`print(x, end="", flush=True)`) shows now
        if self._partial:
            self._writer.write(self._partial)
            self._partial = ""
