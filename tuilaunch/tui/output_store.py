"""Scrollback for the output panes: bounded per process, filterable by ROS level and text.

Plain Python, so the views can be tested without a terminal; the log files keep what the
bounds drop. Each line is parsed once on arrival (level, ROS stamp, logger, message) so a
pane can show a compact form without parsing again on every repaint.
"""

from __future__ import annotations

import re
import time
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from ..engine.plan.model import Plan
from ..engine.run.session.protocol import with_stamp
from ..engine.run.vocabulary.reported_names import ROS_LOG_PREFIX, ReportedNames, current_node_name
from ..engine.run.vocabulary.text import expand_tabs, screen_str, strip_ansi

LEVELS = ("DEBUG", "INFO", "WARN", "ERROR", "FATAL")
INFO = 1
WARN = 2
ERROR = 3
_ROS_PREFIX = ROS_LOG_PREFIX


@dataclass(frozen=True, slots=True)
class Gap:
    """Lines of one process a flood kept off the screen, where its log file has them: the
    `count` lines after the first `skip` from byte `start` (the session's `read_log`)."""

    start: int
    skip: int
    count: int


@dataclass(slots=True, eq=False)
class Line:
    """Mutable for one reason: a line that came over a link without its ROS stamp gets it
    when a pane shows it (`Unstamped`); found by identity, never compared."""

    process: str
    text: str  # as the process printed it, without colour codes, tabs expanded
    level: int  # index into LEVELS
    stamp: float = 0.0  # the ROS stamp when the line has one, else the arrival time
    body: int = 0  # where the message starts after the `[LEVEL] [stamp] [logger]:` prefix
    event: bool = False  # written by tuilaunch (started, died, respawning), not by the process
    gap: Gap | None = None
    """On the line that stands for lines not drawn: where they are, to read them when the
    user scrolls back to it."""
    colored: str | None = None
    """The line with the program's own colour codes, shown by `f` (as printed); kept only
    where they say more than one colour over the whole line, which its level shows."""

    def formatted(self, prefixed: bool) -> str:
        """The full line, as saved or copied: `[id] ` before it in the all-nodes view."""
        return f"[{self.process}] {self.text}" if prefixed else self.text

    @property
    def message(self) -> str:
        return self.text[self.body:]


def level_of(text: str, stream: str) -> int:
    match = _ROS_PREFIX.match(text)
    if match:
        name = match.group(1)
        return LEVELS.index("WARN" if name == "WARNING" else name)
    # unlevelled: print() output is INFO; stderr without a level (tracebacks) is WARN
    return WARN if stream == "stderr" else INFO


class Parsed(NamedTuple):
    line: Line
    logger: str | None  # the logger name it reports (`r1.talker`), if it has the ROS prefix
    unstamped: bool  # the ROS prefix without its stamp (left out over a link: `Unstamped`)


def parse(process: str, raw: str, stream: str, now: float) -> Parsed:
    """A Line, as it arrived `now`, and what its ROS prefix says."""
    # colours are shown by level, never as raw escapes; tabs become spaces once, here, on
    # arrival, after the colour codes (which take no columns) are gone: every repaint,
    # search highlight, pan and wrap then measures the text as drawn
    text = expand_tabs(strip_ansi(raw))
    colored = raw if "\x1b" in raw and not _ONE_COLOUR.fullmatch(raw) else None
    match = _ROS_PREFIX.match(text)
    if not match:
        return Parsed(Line(process, text, WARN if stream == "stderr" else INFO, now,
                           colored=colored), None, False)
    name = match.group(1)
    stamp = float(match.group(2)) if match.group(2) else now
    return Parsed(Line(process, text, LEVELS.index("WARN" if name == "WARNING" else name),
                       stamp, match.end(), colored=colored), match.group(3) or None,
                  not match.group(2))


_ONE_COLOUR = re.compile(r"(\x1b\[[0-9;]*m)?[^\x1b]*(\x1b\[0?m)?")
"""A line in one colour, or none, as a ROS logger colours each line by its level."""


@dataclass
class View:
    """What a pane shows: one process or all, from a level up, lines containing a text."""

    process: str | None = None
    min_level: int = 0
    text: str = ""

    def accepts(self, line: Line) -> bool:
        if line.gap is not None:  # lines of any level and text may be in it
            return self.process is None or line.process == self.process
        return ((self.process is None or line.process == self.process)
                and line.level >= self.min_level
                and (not self.text or self.text.lower() in line.text.lower()))


@dataclass
class Dropped:
    """Lines a flood kept off the screen (all of them are in the log files)."""

    per_process: dict[str, int] = field(default_factory=dict)
    total: int = 0


class OutputStore:
    def __init__(self, scrollback: int = 5000, all_scrollback: int = 20000) -> None:
        self.scrollback = scrollback
        self._per_process: dict[str, deque[Line]] = {}
        self._all: deque[Line] = deque(maxlen=all_scrollback)
        self.dropped = Dropped()
        # the node names processes report in their log lines' logger field, for nodes whose
        # launch file does not name them: process id -> {`/ns/name`, ...} (a few at most)
        self.reported = ReportedNames()
        self.reported_names = self.reported.names
        self.partials: dict[tuple[str, str], Line] = {}
        """The unfinished line each process's stream left waiting (a prompt such as gdb's
        `(gdb) `), by (process, stream): shown below its lines until the whole line comes."""
        self.partials_changed = 0
        """Counts changes to `partials`, so a pane redraws them only when they change."""
        self.unstamped = Unstamped(all_scrollback)

    def node_name(self, plan: Plan, process: str) -> str:
        """The ROS name of a process's node: its plan's, else the one it reports in its
        lines (the process id while it has said none)."""
        return current_node_name(plan.process(process).full_name,
                                 self.reported_names.get(process, ())) or process

    def add(self, process: str, stream: str, texts: Iterable[str],
            first: int | None = None) -> list[Line]:
        """`first`: the number of the first of these lines in a link's stream that leaves
        ROS stamps out until a pane shows them (`Unstamped`)."""
        now = time.time()
        lines: list[Line] = []
        for raw in texts:
            line, logger, unstamped = parse(process, raw, stream, now)
            if logger:
                self.reported.add_logger(process, logger)
            if first is not None and unstamped:
                self.unstamped.add(first + len(lines), line)
            lines.append(line)
        if lines and self.partials.pop((process, stream), None) is not None:
            self.partials_changed += 1  # the whole line replaces what was shown of it
        return self._keep(process, lines)

    def set_partial(self, process: str, stream: str, text: str) -> None:
        """The line a process left unfinished, as it stands (empty: none)."""
        if text:
            self.partials[(process, stream)] = parse(process, text, stream, time.time())[0]
        elif self.partials.pop((process, stream), None) is None:
            return
        self.partials_changed += 1

    def partial_lines(self, view: View) -> list[Line]:
        return [line for line in self.partials.values() if view.accepts(line)]

    def add_event(self, process: str, text: str, level: int = INFO) -> list[Line]:
        """A line from tuilaunch about the process (it started, died, respawns)."""
        return self._keep(process, [Line(process, expand_tabs(text), level, time.time(), 0,
                                         True)])

    def count_dropped(self, process: str, count: int) -> None:
        self.dropped.per_process[process] = self.dropped.per_process.get(process, 0) + count
        self.dropped.total += count

    def add_gap(self, process: str, gap: Gap) -> list[Line]:
        """A line where a flood's lines were not drawn, standing for them until read."""
        return self._keep(process, [gap_line(process, gap, time.time())])

    def fill_gap(self, marker: Line, rows: list[list[Any]], rest: Gap | None,
                 rest_first: bool) -> list[Line]:
        """The gap's lines read from the log file (`read_log`'s `[time, stream, text]`) in
        place of its marker, with a marker for the `rest` not read yet before them
        (`rest_first`) or after them; what replaces the marker."""
        lines = read_back(marker.process, rows)
        if rest is not None:
            left = gap_line(marker.process, rest, marker.stamp)
            lines = [left, *lines] if rest_first else [*lines, left]
        for bucket in (self._per_process.get(marker.process), self._all):
            if bucket is not None:
                replace_line(bucket, marker, lines)
        drawn = len(rows)
        self.dropped.per_process[marker.process] = max(
            self.dropped.per_process.get(marker.process, 0) - drawn, 0)
        self.dropped.total = max(self.dropped.total - drawn, 0)
        return lines

    def _keep(self, process: str, lines: list[Line]) -> list[Line]:
        bucket = self._per_process.setdefault(process, deque(maxlen=self.scrollback))
        bucket.extend(lines)
        self._all.extend(lines)
        return lines

    def lines(self, view: View) -> list[Line]:
        source = self._all if view.process is None else self._per_process.get(view.process, ())
        return [line for line in source if view.accepts(line)]

    def text(self, view: View) -> list[str]:
        return [line.formatted(view.process is None) for line in self.lines(view)]


class Unstamped:
    """The lines that came over a link without their ROS stamp (left out while no pane
    shows it: see the session protocol's `stamps`), by their number in the link's stream,
    oldest first, until they get it. Bounded like the all-nodes scrollback: an older line
    has left every pane but its own, and keeps its arrival time there."""

    def __init__(self, bound: int) -> None:
        # (number, line), numbers rising: the stream's order
        self.lines: deque[tuple[int, Line]] = deque(maxlen=bound)

    def add(self, number: int, line: Line) -> None:
        self.lines.append((number, line))

    def first(self) -> int | None:
        return self.lines[0][0] if self.lines else None

    def fill(self, first: int, end: int, stamps: dict[int, int]) -> int:
        """The stamps (ms) read for the lines numbered up to `end` (lines from `first` on
        are the ones still kept where they were sent); the lines before `end` that have
        none keep their arrival time. How many lines changed."""
        filled = 0
        while self.lines and self.lines[0][0] < end:
            number, line = self.lines.popleft()
            ms = stamps.get(number) if number >= first else None
            if ms is None:
                continue
            text = with_stamp(line.text, ms)
            line.body += len(text) - len(line.text)
            line.text, line.stamp = text, ms / 1000
            filled += 1
        return filled


def read_back(process: str, rows: list[list[Any]]) -> list[Line]:
    """Lines of `process` read from its log file (`read_log`'s `[time, stream, text]`)."""
    return [parse(process, screen_str(str(text)), str(stream), float(at))[0]
            for at, stream, text in rows]


def gap_line(process: str, gap: Gap, stamp: float) -> Line:
    # one row beside the tree at 80 columns: the status line says "in log" already
    return Line(process, f"{gap.count} lines not drawn: scroll here to read", INFO, stamp, 0,
                True, gap)


def replace_line(bucket: deque[Line], old: Line, new: list[Line]) -> int | None:
    """`old` (found by identity) replaced by `new`, the bound dropping the oldest lines;
    where `old` was in `bucket`, or None when it is not there."""
    items = list(bucket)
    for index in range(len(items) - 1, -1, -1):
        if items[index] is old:
            items[index:index + 1] = new
            bucket.clear()
            bucket.extend(items)
            return index
    return None
