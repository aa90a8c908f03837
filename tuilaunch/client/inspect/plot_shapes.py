"""What a plot of several fields is shaped into, as plain decisions the tests read without a
terminal: the command line's words into topics and their fields, the fields into panels
of readable scales, two fields into XY pairs, and the CSV a plot writes (`--csv`: every
message; the plot screen's `S`: what it holds).
"""

from __future__ import annotations

import heapq
import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from ...engine.run.session.session_dir import SessionError
from .plot_series import PlotSeries, Point

READABLE = 10.0
"""A field whose own range is less than 1/READABLE of its panel's range draws as a flat
line there: fields that far apart get panels of their own."""


# --- the command line ----------------------------------------------------------------------

@dataclass
class Asked:
    """One topic of one session, and the fields the command line asks of it."""

    session: str
    topic: str
    fields: list[str]


def is_session_word(word: str) -> bool:
    """`robot2:base`, `local:sim`: a field never holds a colon, a topic starts with `/`."""
    return ":" in word and not word.startswith("/")


def command_words(session: str, topic: str, words: list[str]) -> list[Asked]:
    """`SESSION TOPIC FIELD... [[SESSION] TOPIC FIELD...]`: a word starting with `/` starts a
    topic, a `HOST:NAME` (or `local:NAME`) word another session; SessionError names the
    word that has no place."""
    asked = [Asked(session, topic, [])]
    current_session = session
    usage = "plot NAME TOPIC FIELD ... [[HOST:]NAME] [TOPIC FIELD ...]"
    pending_session: str | None = None
    for word in words:
        if pending_session is not None:
            if not word.startswith("/"):
                raise SessionError(f"{pending_session} is followed by {word!r}, not a topic "
                                   f"(/name): {usage}")
            current_session, pending_session = pending_session, None
            asked.append(Asked(current_session, word, []))
        elif is_session_word(word):
            pending_session = word
        elif word.startswith("/"):
            asked.append(Asked(current_session, word, []))
        else:
            asked[-1].fields.append(word)
        if pending_session is None and len(asked) > 1 and not asked[-2].fields:
            raise SessionError(f"{asked[-2].topic} has no field to plot: {usage}")
    if pending_session is not None:
        raise SessionError(f"{pending_session} is followed by no topic: {usage}")
    if not asked[-1].fields:
        raise SessionError(f"{asked[-1].topic} has no field to plot: {usage}")
    merged: dict[tuple[str, str], Asked] = {}
    for one in asked:  # a topic named twice is one stream: its fields together
        kept = merged.setdefault((one.session, one.topic), Asked(one.session, one.topic, []))
        kept.fields += [f for f in one.fields if f not in kept.fields]
    return list(merged.values())


# --- scales --------------------------------------------------------------------------------

def panels(ranges: dict[str, tuple[float, float]]) -> list[list[str]]:
    """The columns grouped so that each reads on its panel's y axis: a column joins the
    first panel where its range and every other's stay at least 1/READABLE of the panel's
    (a constant field fits anywhere); one panel when they all read together."""
    groups: list[list[str]] = []
    spans: list[tuple[float, float]] = []

    def readable(low: float, high: float, union: tuple[float, float]) -> bool:
        own = high - low
        return own == 0 or own * READABLE >= union[1] - union[0]

    for column, (low, high) in ranges.items():
        for index, members in enumerate(groups):
            union = (min(spans[index][0], low), max(spans[index][1], high))
            if readable(low, high, union) and all(
                    readable(*ranges[m], union) for m in members):
                members.append(column)
                spans[index] = union
                break
        else:
            groups.append([column])
            spans.append((low, high))
    return groups


# --- XY ------------------------------------------------------------------------------------

def xy_pairs(xs: list[Point], ys: list[Point]) -> tuple[list[float], list[float]]:
    """Each point of the y field against the x field's value at that time (the latest at or
    before it: the same bucket for two fields of one topic), by their last values."""
    out_x: list[float] = []
    out_y: list[float] = []
    i = 0
    current: float | None = None
    for t, _low, _high, last in ys:
        while i < len(xs) and xs[i][0] <= t + 1e-9:
            current = xs[i][3]
            i += 1
        if current is not None:
            out_x.append(current)
            out_y.append(last)
    return out_x, out_y


# --- CSV -----------------------------------------------------------------------------------

def csv_cell(value: Any) -> str:
    """A value as the CSV prints it: exact (repr, the shortest that reads back the same),
    an integer field without a decimal point, nothing where a message had no value (an
    index past a sequence's end, a field of another topic's message)."""
    if value is None:
        return ""
    return str(value) if isinstance(value, int) else repr(float(value))


def time_cell(value: float) -> str:
    return f"{value:.6f}"


class RowMerge:
    """`--csv` of several streams: rows of every message, one line each, in time order
    across the streams. Each stream's rows come in its own batches (ten a second), so a
    row is held until every stream that sends has sent one as late, or for HOLD_S."""

    HOLD_S = 0.5

    def __init__(self, widths: list[int], relative: bool) -> None:
        """`widths`: the columns of each stream, in order; `relative`: the time in seconds
        since the first row (else as it came: epoch seconds of header.stamp)."""
        self.offsets = [sum(widths[:i]) for i in range(len(widths))]
        self.widths = widths
        self.total = sum(widths)
        self.relative = relative
        self.first: float | None = None
        self.heap: list[tuple[float, int, int, float, list[Any]]] = []
        self.latest: list[float | None] = [None] * len(widths)
        self.count = 0

    def add(self, stream: int, rows: Iterable[list[Any]], now: float) -> None:
        """A stream's rows ([time, value, ...]), received at `now` (monotonic)."""
        for row in rows:
            self.count += 1
            heapq.heappush(self.heap, (float(row[0]), self.count, stream, now, row[1:]))
            self.latest[stream] = float(row[0])

    def lines(self, now: float, final: bool = False) -> list[str]:
        """The lines of the rows no stream can come before any more (each stream sent one
        as late), or held HOLD_S already; `final`: all of them."""
        known = [t for t in self.latest if t is not None]
        watermark = math.inf if final else \
            (min(known) if len(known) == len(self.latest) else -math.inf)
        out: list[str] = []
        while self.heap and (self.heap[0][0] <= watermark or
                             self.heap[0][3] <= now - self.HOLD_S):
            t, _, stream, _received, values = heapq.heappop(self.heap)
            cells = [""] * self.total
            start = self.offsets[stream]
            cells[start:start + self.widths[stream]] = [csv_cell(v) for v in values]
            if self.first is None:
                self.first = t
            shown = t - self.first if self.relative else t
            out.append(time_cell(shown) + "," + ",".join(cells) + "\n")
        return out


def series_csv(series: PlotSeries, window: float | None = None,
               end: float | None = None) -> tuple[str, int]:
    """What a plot holds as CSV (the plot screen's `S`), and its number of rows: `time`
    (epoch seconds: of arrival, or the messages' header.stamp), then each column's last
    value and its min and max over the 1/20 s the point folds (the server's decimation);
    a row per point, of one topic (the others' cells empty). `window`: only the points
    within it, ending at `end`."""
    columns = series.columns
    header = ["time"]
    for column in columns:
        header += [column, f"{column} min", f"{column} max"]
    rows: dict[tuple[float, int], list[str]] = {}
    for source_index, source in enumerate(series.sources):
        for path in source.fields:
            column = series.column(source, path)
            at = 3 * columns.index(column) + 1
            kept = list(series.points.get(column) or [])
            if window is not None and end is not None:
                kept = series.shown(column, window, end)
            for t, low, high, last in kept:
                row = rows.setdefault((t, source_index), [""] * len(header))
                row[0] = time_cell(t)
                row[at:at + 3] = [repr(last), repr(low), repr(high)]
    lines = [",".join(header)] + [",".join(rows[key]) for key in sorted(rows)]
    return "\n".join(lines) + "\n", len(rows)
