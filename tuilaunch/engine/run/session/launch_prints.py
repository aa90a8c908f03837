"""What launch-file code prints while a session runs: a line of the launch, not lost.

A session server has no terminal: its stdout is its session.log. A `print()` in an
OpaqueFunction, an event callback or an OpaqueCoroutine, which ros2 launch shows on its
terminal, would be seen by nobody. Here each whole line becomes a launch line, as the
supervisor's own are: in every client's all-nodes pane, in launch.log and `tuilaunch logs`,
and still in session.log.
"""

from __future__ import annotations

import asyncio
import io
import threading
from collections.abc import Callable
from typing import TextIO


class LaunchPrints(io.TextIOBase):
    """`sys.stdout` of a session server: `say` gets each whole line on the loop's thread."""

    def __init__(self, say: Callable[[str], None], original: TextIO,
                 loop: asyncio.AbstractEventLoop) -> None:
        self._say = say
        self._original = original
        self._loop = loop
        self._loop_thread = threading.get_ident()
        self._partial = ""

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        if not isinstance(text, str):
            raise TypeError(f"write() argument must be str, not {type(text).__name__}")
        self._original.write(text)
        data = self._partial + text
        *lines, self._partial = data.split("\n")
        for line in lines:
            if threading.get_ident() == self._loop_thread:
                self._say(line)
            else:  # a thread the file started: the supervisor is the loop's alone
                self._loop.call_soon_threadsafe(self._say, line)
        return len(text)

    def flush(self) -> None:
        self._original.flush()
