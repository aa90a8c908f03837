"""A bounded buffer between the supervisor and a consumer that draws at its own pace.

Process reading never waits for a display: past `max_lines`, the oldest output lines are
dropped from the buffer and counted per process. Only the display loses them; the log
files already hold every line. Other events (started, exited, ...) are never dropped.
"""

from __future__ import annotations

import threading
from collections import deque

from .supervisor import Event


class EventBuffer:
    def __init__(self, max_lines: int = 20_000) -> None:
        self.max_lines = max_lines
        self._events: deque[Event] = deque()
        self._lines = 0
        self._dropped: dict[str, int] = {}
        self._lock = threading.Lock()
        self.total_dropped = 0

    def __call__(self, event: Event) -> None:
        with self._lock:
            self._events.append(event)
            if event.kind == "output":
                self._lines += len(event.lines)
                if self._lines > self.max_lines:
                    self._trim()

    def _trim(self) -> None:
        excess = self._lines - self.max_lines
        kept: deque[Event] = deque()
        for event in self._events:
            if excess > 0 and event.kind == "output":
                cut = min(excess, len(event.lines))
                excess -= cut
                self._lines -= cut
                self.total_dropped += cut
                name = event.process or ""
                self._dropped[name] = self._dropped.get(name, 0) + cut
                if cut == len(event.lines):
                    continue
                event.lines = event.lines[cut:]
            kept.append(event)
        self._events = kept

    def drain(self) -> list[Event]:
        """Everything buffered, oldest first, after one `dropped` event per process that lost
        lines since the last drain (`code` is the count)."""
        with self._lock:
            events = list(self._events)
            dropped = self._dropped
            self._events = deque()
            self._lines = 0
            self._dropped = {}
        notices = [Event("dropped", name, code=count,
                         reason=f"{count} lines not shown (all are in the log file)")
                   for name, count in dropped.items()]
        return notices + events
