"""A plot's points as a client keeps them: the buckets the session server sends (`plot`
events: [ms after t0, min, max, last] per bucket and field, engine/ros/plot/streams.py),
the last five minutes of each plotted field of each topic (of each session), and what a
window of them shows (rebinned to the plot's width, each bin still keeping its min and
max, and each field's last, min and max).

A plot shows fields of several topics, of several sessions: each topic of a session is a
`Source`, one stream of the server's, told apart by its tag; each of its fields is a
column, named `TOPIC/FIELD` (`SESSION:TOPIC/FIELD` once several sessions are plotted), as
the CSV names it.

No Textual here: the TUI's plot screen and `tuilaunch plot` draw from it, tests read it.
"""

from __future__ import annotations

import itertools
import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

KEEP_S = 300.0
"""Seconds of points kept per field: the longest window (5 min)."""
WINDOWS = (10.0, 60.0, 300.0)
"""The windows a plot switches between, in seconds."""
Point = tuple[float, float, float, float]
"""A bucket as sent: (time, min, max, last)."""
_TAGS = itertools.count(1)


def new_tag() -> str:
    """A stream's tag, unique in this process: events of a stream replaced (or of another
    session's plot) are told apart whatever session sent them."""
    return f"p{next(_TAGS)}"


def column_name(session: str, topic: str, path: str, with_session: bool) -> str:
    """`TOPIC/FIELD`, or `SESSION:TOPIC/FIELD` when several sessions are plotted."""
    name = f"{topic.rstrip('/')}/{path}"
    return f"{session}:{name}" if with_session else name


@dataclass
class Source:
    """One topic of one session on a plot, and the fields of it plotted."""

    session: str
    """The session as the user named it (`robot1:sig`), or `""` for the only one."""
    topic: str
    fields: list[str]
    tag: str = field(default_factory=new_tag)
    type_name: str = ""
    stamped: bool = False
    """The type has a header.stamp (the server says it when the stream starts)."""


@dataclass(frozen=True)
class Stats:
    """A field's figures over the window shown."""

    last: float
    low: float
    high: float


class PlotSeries:
    """The points of the columns one plot shows, from the events of its sources' streams."""

    def __init__(self, sources: list[Source] | None = None) -> None:
        self.sources: list[Source] = []
        self.points: dict[str, deque[Point]] = {}
        self.received = 0
        for source in sources or []:
            self.put(source)

    # --- what is plotted ----------------------------------------------------------------------

    @property
    def several_sessions(self) -> bool:
        return len({s.session for s in self.sources}) > 1

    def column(self, source: Source, path: str) -> str:
        return column_name(source.session, source.topic, path, self.several_sessions)

    @property
    def columns(self) -> list[str]:
        """Every plotted field's column, in the order they were asked for."""
        return [self.column(s, path) for s in self.sources for path in s.fields]

    def put(self, source: Source) -> Source | None:
        """Plots `source` (a topic of a session new to the plot, or new fields, a new tag of
        one plotted: its points start again, the server sends what it kept); returns the
        source it replaced."""
        old = self.find(source.session, source.topic)
        if old is not None:
            self.sources[self.sources.index(old)] = source
        else:
            self.sources.append(source)
        self._rename()
        for path in source.fields:
            self.points[self.column(source, path)] = deque()
        return old

    def remove(self, source: Source) -> None:
        self.sources = [s for s in self.sources if s is not source]
        self._rename()

    def find(self, session: str, topic: str) -> Source | None:
        return next((s for s in self.sources if s.session == session and s.topic == topic),
                    None)

    def _rename(self) -> None:
        """Columns follow what is plotted (a second session adds its name to every one)."""
        kept: dict[str, deque[Point]] = {}
        for source in self.sources:
            for path in source.fields:
                column = self.column(source, path)
                kept[column] = self.points.get(column) or \
                    self.points.get(column_name(source.session, source.topic, path,
                                                not self.several_sessions)) or deque()
        self.points = kept

    def clear(self) -> None:
        for kept in self.points.values():
            kept.clear()

    # --- points ------------------------------------------------------------------------------

    def add(self, data: dict[str, Any]) -> bool:
        """A `plot` event's points; False when they are not this plot's (another stream's,
        or one replaced, still on its way)."""
        source = next((s for s in self.sources if s.tag == data.get("tag")), None)
        if source is None:
            return False
        since = float(data.get("t0") or 0)  # each point's time is in ms after it
        for path, points in (data.get("points") or {}).items():
            kept = self.points.get(self.column(source, path))
            if kept is None or path not in source.fields:
                continue
            for ms, low, high, last in points:
                t = since + ms / 1000
                if kept and t <= kept[-1][0]:
                    continue  # sent again (a reconnection, a backfill): kept once
                kept.append((float(t), float(low), float(high), float(last)))
                self.received += 1
            while kept and kept[0][0] < kept[-1][0] - KEEP_S:
                kept.popleft()
        return True

    def newest(self, columns: list[str] | None = None) -> float | None:
        """The time of the newest point of any field, or of `columns` (the right end of
        the plot)."""
        times = [kept[-1][0] for column, kept in self.points.items()
                 if kept and (columns is None or column in columns)]
        return max(times) if times else None

    def held(self) -> float:
        """Seconds of points held: the longest any field spans."""
        return max((kept[-1][0] - kept[0][0] for kept in self.points.values() if kept),
                   default=0.0)

    def shown(self, column: str, window: float, end: float) -> list[Point]:
        """The points of `column` within (end - window, end]."""
        kept: deque[Point] = self.points.get(column) or deque()
        start = end - window
        found: list[Point] = []
        for point in reversed(kept):
            if point[0] <= start:
                break
            if point[0] <= end:
                found.append(point)
        found.reverse()
        return found

    def stats(self, column: str, window: float, end: float) -> Stats | None:
        points = self.shown(column, window, end)
        if not points:
            return None
        return Stats(points[-1][3], min(p[1] for p in points), max(p[2] for p in points))


def rebinned(points: list[Point], start: float, end: float, bins: int)\
        -> tuple[list[float], list[float]]:
    """The x and y a line plot draws of `points` across `bins` columns: each bin's min
    and max (a spike one sample wide is its bin's max), in the order that joins the line
    to its neighbours; a bin of one value is one point."""
    if not points or bins < 1 or end <= start:
        return [], []
    width = (end - start) / bins
    xs: list[float] = []
    ys: list[float] = []
    current: list[Any] | None = None  # [bin, t, low, high, last]

    def flush(bucket: list[Any]) -> None:
        _, t, low, high, _last = bucket
        previous = ys[-1] if ys else low
        pair = (low, high) if abs(previous - low) <= abs(previous - high) else (high, low)
        for value in (pair if low != high else (low,)):
            xs.append(t)
            ys.append(value)

    for t, low, high, last in points:
        index = min(math.floor((t - start) / width), bins - 1)
        if current is not None and current[0] == index:
            current[1] = t
            current[2] = min(current[2], low)
            current[3] = max(current[3], high)
            current[4] = last
            continue
        if current is not None:
            flush(current)
        current = [index, t, low, high, last]
    if current is not None:
        flush(current)
    return xs, ys
