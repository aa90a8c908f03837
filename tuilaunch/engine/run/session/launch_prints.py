"""What launch-file code prints while a launch runs: whole lines, handed on.

`PrintedLines` stands in for `sys.stdout` and hands on whole lines; the rest of the stream
(its file descriptor, whether it is a terminal, its encoding) stays the original's, so code
that gives `sys.stdout` to a subprocess still works. Headless, the lines join the stdout
writer's queue (cli/stdout_writer.py's LineJoiner).

A session server has no terminal: its stdout is its session.log. A `print()` in an
OpaqueFunction, an event callback or an OpaqueCoroutine, which ros2 launch shows on its
terminal, would be seen by nobody. `LaunchPrints` makes each whole line a launch line, as
the supervisor's own are: in every client's all-nodes pane, in launch.log, and still in
session.log.
"""

from __future__ import annotations

import asyncio
import io
import threading
from collections.abc import Callable
from typing import TextIO


class PrintedLines(io.TextIOBase):
    """`sys.stdout` whose whole lines go to `_whole` (a block of lines, each ending in
    `\\n`); what follows the last newline waits for the rest of its line."""

    def __init__(self, original: TextIO) -> None:
        self._original = original
        self._partial = ""

    def _whole(self, block: str) -> None:
        raise NotImplementedError

    def write(self, text: str) -> int:
        if not isinstance(text, str):
            raise TypeError(f"write() argument must be str, not {type(text).__name__}")
        data = self._partial + text
        end = data.rfind("\n") + 1
        if end:
            self._whole(data[:end])
        self._partial = data[end:]
        return len(text)

    def writable(self) -> bool:
        return True

    def fileno(self) -> int:
        return self._original.fileno()

    def isatty(self) -> bool:
        return self._original.isatty()

    @property
    def encoding(self) -> str:  # type: ignore[override]
        return self._original.encoding


class LaunchPrints(PrintedLines):
    """`sys.stdout` of a session server: `say` gets each whole line on the loop's thread."""

    def __init__(self, say: Callable[[str], None], original: TextIO,
                 loop: asyncio.AbstractEventLoop) -> None:
        super().__init__(original)
        self._say = say
        self._loop = loop
        self._loop_thread = threading.get_ident()

    def write(self, text: str) -> int:
        written = super().write(text)
        self._original.write(text)  # session.log keeps it as printed, line ends or not
        return written

    def _whole(self, block: str) -> None:
        for line in block[:-1].split("\n"):
            if threading.get_ident() == self._loop_thread:
                self._say(line)
            else:  # a thread the file started: the supervisor is the loop's alone
                self._loop.call_soon_threadsafe(self._say, line)

    def flush(self) -> None:
        self._original.flush()
