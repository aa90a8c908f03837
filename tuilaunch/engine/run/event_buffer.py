"""A bounded buffer between the supervisor and a consumer that draws at its own pace.

Process reading never waits for a display: past `max_lines`, the oldest output lines are
dropped from the buffer and counted per process. Only the display loses them; the log
files already hold every line. Other events (started, exited, ...) are never dropped.
`fair`: the lines dropped are the oldest of the process holding the most, so a display
sent few lines a second (over an ssh link) still sees every node, not only the loudest.
"""

from __future__ import annotations

import dataclasses
import itertools
import threading
from collections import deque

from .events import Dropped, Event, Output

MAX_BYTES = 32 << 20
"""Output text a buffer holds at most, whatever its count of lines: lines are kept whole up
to 8 MiB (process/output.py), so a count alone would let a few thousand long lines take
gigabytes for a display that reads slowly."""


class EventBuffer:
    def __init__(self, max_lines: int = 20_000, fair: bool = False,
                 max_bytes: int = MAX_BYTES) -> None:
        self.max_lines = max_lines
        self.max_bytes = max_bytes
        self.fair = fair
        self._held: dict[str, int] = {}  # lines buffered per process
        # two queues, merged by sequence number on drain, so trimming output is O(1) per
        # event however much other traffic is waiting
        self._output: deque[tuple[int, Event]] = deque()
        self._other: list[tuple[int, Event]] = []
        self._sequence = itertools.count()
        self._lines = 0
        self._bytes = 0  # the characters of the lines held
        self._dropped: dict[str, int] = {}
        self._lock = threading.Lock()
        self.total_dropped = 0

    def __call__(self, event: Event) -> None:
        with self._lock:
            entry = (next(self._sequence), event)
            if not isinstance(event, Output):
                self._other.append(entry)
                return
            self._output.append(entry)
            self._lines += len(event.lines)
            self._bytes += sum(map(len, event.lines))
            name = event.process or ""
            self._held[name] = self._held.get(name, 0) + len(event.lines)
            while self._lines > self.max_lines:
                self._trim(self._lines - self.max_lines)
            while self._bytes > self.max_bytes and len(self._output) > 1:
                self._trim(None)

    def _trim(self, excess: int | None) -> None:
        """Drops `excess` lines (None: as many as bring the text under max_bytes, at least
        one), the oldest first, or the loudest process's oldest when fair."""
        index = 0
        if self.fair:
            # a scan, but a fair buffer is a small one (a screenful a second)
            loudest = max(self._held, key=lambda name: self._held[name])
            index = next(i for i, (_, event) in enumerate(self._output)
                         if (event.process or "") == loudest)
        _, oldest = self._output[index]
        if excess is None:
            over, excess = self._bytes - self.max_bytes, 0
            for line in oldest.lines:
                excess += 1
                over -= len(line)
                if over <= 0:
                    break
        cut = min(excess, len(oldest.lines))
        name = oldest.process or ""
        self._dropped[name] = self._dropped.get(name, 0) + cut
        self.total_dropped += cut
        self._lines -= cut
        self._bytes -= sum(map(len, oldest.lines[:cut]))
        self._held[name] -= cut
        if cut == len(oldest.lines):
            del self._output[index]
        else:
            oldest.lines = oldest.lines[cut:]

    def drain(self) -> list[Event]:
        """Everything buffered, oldest first, after one `dropped` event per process that lost
        lines since the last drain (`code` is the count)."""
        with self._lock:
            entries = sorted([*self._output, *self._other], key=lambda entry: entry[0])
            dropped = self._dropped
            self._output = deque()
            self._other = []
            self._lines = 0
            self._bytes = 0
            self._held = {}
            self._dropped = {}
        notices = [Dropped(name, code=count,
                           reason=f"{count} lines not shown (all are in the log file)")
                   for name, count in dropped.items()]
        return notices + joined([event for _, event in entries])


def joined(events: list[Event]) -> list[Event]:
    """Consecutive output events of one process and stream as one (the first's time): a
    batch then carries each run of lines once, not a header per read of the pipe."""
    out: list[Event] = []
    for event in events:
        last = out[-1] if out else None
        if (last is not None and isinstance(event, Output) and isinstance(last, Output)
                and last.process == event.process and last.stream == event.stream
                and last.pid == event.pid and last.level == event.level
                and last.data is None and event.data is None):
            out[-1] = dataclasses.replace(last, lines=[*last.lines, *event.lines])
            continue
        out.append(event)
    return out
