"""Scrollback for the output panes: bounded per process, filterable by ROS level and text.

Plain Python, so the views can be tested without a terminal; the log files keep what the
bounds drop.
"""

from __future__ import annotations

import re
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass

from .engine.run.output import strip_ansi

LEVELS = ("DEBUG", "INFO", "WARN", "ERROR", "FATAL")
_LEVEL = re.compile(r"^\[(DEBUG|INFO|WARN|WARNING|ERROR|FATAL)\]")


@dataclass(frozen=True)
class Line:
    process: str
    text: str
    level: int  # index into LEVELS

    def formatted(self, prefixed: bool) -> str:
        return f"[{self.process}] {self.text}" if prefixed else self.text


def level_of(text: str, stream: str) -> int:
    match = _LEVEL.match(text)
    if match:
        name = match.group(1)
        return LEVELS.index("WARN" if name == "WARNING" else name)
    # unlevelled: print() output is INFO; stderr without a level (tracebacks) is WARN
    return LEVELS.index("WARN") if stream == "stderr" else LEVELS.index("INFO")


@dataclass
class View:
    """What a pane shows: one process or all, from a level up, lines containing a text."""

    process: str | None = None
    min_level: int = 0
    text: str = ""

    def accepts(self, line: Line) -> bool:
        return ((self.process is None or line.process == self.process)
                and line.level >= self.min_level
                and (not self.text or self.text.lower() in line.text.lower()))


class OutputStore:
    def __init__(self, scrollback: int = 5000, all_scrollback: int = 20000) -> None:
        self.scrollback = scrollback
        self._per_process: dict[str, deque[Line]] = {}
        self._all: deque[Line] = deque(maxlen=all_scrollback)

    def add(self, process: str, stream: str, texts: Iterable[str]) -> list[Line]:
        lines = []
        for raw in texts:
            text = strip_ansi(raw)  # colours are shown by level, never as raw escapes
            lines.append(Line(process, text, level_of(text, stream)))
        bucket = self._per_process.setdefault(process, deque(maxlen=self.scrollback))
        bucket.extend(lines)
        self._all.extend(lines)
        return lines

    def lines(self, view: View) -> list[Line]:
        source = self._all if view.process is None else self._per_process.get(view.process, ())
        return [line for line in source if view.accepts(line)]

    def text(self, view: View) -> list[str]:
        return [line.formatted(view.process is None) for line in self.lines(view)]
