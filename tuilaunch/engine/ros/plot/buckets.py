"""Decimation for plots: a field's samples folded into time buckets of a fixed width, each
keeping its min, max and last value, so a plot of a 1 kHz topic costs the link what a plot
of a 20 Hz one does and a one-sample spike still shows (as its bucket's max).

Bucket boundaries are multiples of the width in the server's clock, the same for every
client: two clients plotting one topic are sent the same points. Pure Python, no ROS.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

POINTS_PER_S = 20
"""Buckets a second per field: a 10 s window is 200 points across a terminal's 60-odd
columns (two dots a column in braille), and 1 kHz topics cost 20 points a second."""
KEEP_S = 300.0
"""Seconds of buckets kept per field: the longest window a plot shows (5 min)."""


@dataclass
class Bucket:
    """One bucket: its index (time // width), the time of its last sample, its min, max,
    last value and how many samples it folds."""

    index: int
    time: float
    low: float
    high: float
    last: float
    count: int

    def point(self, since: int = 0) -> list[float]:
        """As sent to a client: [time in ms after the second `since`, min, max, last], six
        significant digits (a plot's resolution is far coarser; the CSV gets every value
        exact instead). An offset in ms is 3 to 6 digits where the time is 14."""
        return [round((self.time - since) * 1000), _short(self.low), _short(self.high),
                _short(self.last)]


def _short(value: float) -> float:
    return value if not math.isfinite(value) else float(f"{value:.6g}")


class FieldBuckets:
    """The closed buckets of one field over the last KEEP_S seconds, and the open one."""

    def __init__(self, width: float = 1.0 / POINTS_PER_S, keep_s: float = KEEP_S) -> None:
        self.width = width
        self.closed: deque[Bucket] = deque(maxlen=max(1, int(keep_s / width)))
        self.open: Bucket | None = None

    def add(self, time: float, value: float) -> None:
        """A sample received at `time` (seconds). NaN is skipped: it has no place on a
        y axis, and would poison min and max."""
        if math.isnan(value):
            return
        index = math.floor(time / self.width)
        bucket = self.open
        if bucket is None and self.closed and index <= self.closed[-1].index:
            # a header.stamp older than what was sent: drawn where the buckets end
            index, time = self.closed[-1].index + 1, max(time, self.closed[-1].time)
        if bucket is not None and index <= bucket.index:
            # the same bucket; or a header.stamp older than it (stamps need not come in
            # order): folded into it, as buckets already sent are not sent again
            bucket.time = max(bucket.time, time)
            bucket.low = min(bucket.low, value)
            bucket.high = max(bucket.high, value)
            bucket.last = value
            bucket.count += 1
            return
        if bucket is not None:
            self.closed.append(bucket)
        self.open = Bucket(index, time, value, value, value, 1)

    def close_until(self, now: float) -> None:
        """Closes the open bucket once its time is over: a slow topic's last bucket is sent
        when its width has passed, not when the next message comes."""
        if self.open is not None and math.floor(now / self.width) > self.open.index:
            self.closed.append(self.open)
            self.open = None

    def since(self, index: int) -> list[Bucket]:
        """The closed buckets after `index`, oldest first."""
        if not self.closed or self.closed[-1].index <= index:
            return []
        found: list[Bucket] = []
        for bucket in reversed(self.closed):
            if bucket.index <= index:
                break
            found.append(bucket)
        found.reverse()
        return found
