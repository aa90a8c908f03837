"""A respawn's wait counted down on the tree's row ("try 8 in 23 s"), not frozen at what it
was when the wait began: one timer a second while some process waits, none otherwise, and
only the rows that changed are drawn again (each is a few bytes over ssh)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

monotonic = time.monotonic
"""The clock a wait is counted on (a test sets one it moves itself: a busy machine's timer
may come late and skip a second, which the row rightly shows)."""


@dataclass
class _Wait:
    tries: int
    due: float
    """When it comes back, on this computer's monotonic clock (a robot's clock may be far
    from ours: the delay is counted from when its event arrived)."""


class RespawnCountdown:
    """The respawn waits under way, by process, and their rows' texts."""

    def __init__(self) -> None:
        self._waits: dict[str, _Wait] = {}

    def begin(self, process: str, tries: int, delay: float,
              now: float | None = None) -> str:
        """A wait begins; returns the row's text for it."""
        start = monotonic() if now is None else now
        self._waits[process] = _Wait(tries, start + delay)
        return self.text(process, start)

    def end(self, process: str) -> None:
        """It came back, was stopped or started: nothing to count any more."""
        self._waits.pop(process, None)

    def __bool__(self) -> bool:
        return bool(self._waits)

    def text(self, process: str, now: float | None = None) -> str:
        wait = self._waits[process]
        left = max(0, math.ceil(wait.due - (monotonic() if now is None else now)))
        return f"(try {wait.tries} in {left} s)"

    def tick(self, now: float | None = None) -> dict[str, str]:
        """The rows' texts now, of every process still waiting."""
        return {process: self.text(process, now) for process in self._waits}
