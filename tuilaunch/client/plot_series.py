"""A plot's points as a client keeps them: the buckets the session server sends (`plot`
events: [ms after t0, min, max, last] per bucket and field, engine/ros/plot/streams.py),
the last five minutes of each field, and what a window of them shows (rebinned to the plot's width,
each bin still keeping its min and max, and each field's last, min and max).

No Textual here: the TUI's plot screen and `tuilaunch plot` draw from it, tests read it.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Any

KEEP_S = 300.0
"""Seconds of points kept per field: the longest window (5 min)."""
WINDOWS = (10.0, 60.0, 300.0)
"""The windows a plot switches between, in seconds."""
Point = tuple[float, float, float, float]
"""A bucket as sent: (time, min, max, last)."""


@dataclass(frozen=True)
class Stats:
    """A field's figures over the window shown."""

    last: float
    low: float
    high: float


class PlotSeries:
    """The points of the fields one plot shows, from the events of its stream (`tag`)."""

    def __init__(self, fields: list[str], tag: Any = None) -> None:
        self.fields = list(fields)
        self.tag = tag
        self.points: dict[str, deque[Point]] = {
            f: deque() for f in self.fields}
        self.received = 0

    def add(self, data: dict[str, Any]) -> bool:
        """A `plot` event's points; False when they are not this plot's (another stream's,
        or the one it replaced, still on its way)."""
        if data.get("tag") != self.tag:
            return False
        since = float(data.get("t0") or 0)  # each point's time is in ms after it
        for path, points in (data.get("points") or {}).items():
            kept = self.points.get(path)
            if kept is None:
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

    def newest(self) -> float | None:
        """The time of the newest point of any field (the right end of the plot)."""
        times = [kept[-1][0] for kept in self.points.values() if kept]
        return max(times) if times else None

    def shown(self, path: str, window: float, end: float) -> list[Point]:
        """The points of `path` within (end - window, end]."""
        kept: deque[Point] = self.points.get(path) or deque()
        start = end - window
        found: list[Point] = []
        for point in reversed(kept):
            if point[0] <= start:
                break
            if point[0] <= end:
                found.append(point)
        found.reverse()
        return found

    def stats(self, path: str, window: float, end: float) -> Stats | None:
        points = self.shown(path, window, end)
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
