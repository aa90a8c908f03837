"""Log files that never stop the launch: a full disk or a dead device costs lines on disk,
never a node's pipe, a shutdown or the other files.

Each write goes straight to the file (no buffer held in tuilaunch), so `tail -f` sees a line
at once and a SIGKILL of tuilaunch loses nothing already read.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Callable
from pathlib import Path

Reporter = Callable[[str], None]

_FLAGS = os.O_WRONLY | os.O_CREAT | os.O_APPEND | os.O_CLOEXEC | getattr(os, "O_NOFOLLOW", 0)


class LogFile:
    """An append-only file; the first failure is reported once, with the file and the reason,
    and again when writing works again, with the count of lines that could not be saved."""

    def __init__(self, path: Path, report: Reporter) -> None:
        self.path = path
        self._report = report
        self._fd: int | None = os.open(path, _FLAGS, 0o644)  # OSError: the caller reports it
        self.lost_lines = 0
        self._failing = False

    def write(self, data: bytes, lines: int = 1) -> None:
        self._write_all([memoryview(data)], lambda: lines)

    def write_stamped(self, stamp: bytes, block: bytes) -> None:
        """Whole lines (`block` ends in `\n`), each line starting with `stamp`: one
        gathered write of the stamp and the block with the stamp after each newline, with
        no copy of the block beyond that one (a flood writes a 4 KB block at a time)."""
        body = memoryview(block.replace(b"\n", b"\n" + stamp))[:-len(stamp)]
        self._write_all([memoryview(stamp), body], lambda: block.count(b"\n"))

    def _write_all(self, views: list[memoryview], lines: Callable[[], int]) -> None:
        if self._fd is None:
            return
        try:
            while views:
                written = os.writev(self._fd, views)
                while views and written >= len(views[0]):
                    written -= len(views[0])
                    views.pop(0)
                if views:
                    views[0] = views[0][written:]
        except OSError as exc:
            self.lost_lines += lines()
            if not self._failing:
                self._failing = True
                self._report(f"cannot write log file {self.path}: "
                             f"{exc.strerror or errno.errorcode.get(exc.errno or 0, exc)}; "
                             "its lines are lost until it can be written again")
            return
        if self._failing:
            self._failing = False
            self._report(f"log file {self.path} is written again; {self.lost_lines} "
                         "line(s) could not be saved")

    def close(self) -> None:
        if self._fd is not None:
            try:
                os.close(self._fd)
            except OSError:
                pass  # a close error on a file we no longer write changes nothing
            self._fd = None

    @property
    def closed(self) -> bool:
        return self._fd is None
