"""The pace and the news of a lost link's reconnection: backoff between attempts (or at
once when asked), the attempt under way and when it began, the latest reason. What a
status line reads (client/link.py's lost_link_line: `retrying (attempt 2, 12 s) · last:
REASON`); the attempts themselves are the caller's (a new Connection each).
"""

from __future__ import annotations

import asyncio
import contextlib
import time

RETRY_FIRST = 1.0
"""Seconds before the first try to reconnect a dropped link; doubled after each failure."""
RETRY_MOST = 15.0
"""The longest wait between tries: a robot back on the network is found within this."""


class Reconnector:
    """One link's reconnection. `down` says why the link is down (None while it is up)."""

    def __init__(self, first: float = RETRY_FIRST, most: float = RETRY_MOST) -> None:
        self.first, self.most = first, most
        self.down: str | None = None
        """While the link is down: why ("link to HOST lost (reason)")."""
        self.reason: str | None = None
        """While it is down: the latest attempt's reason (the first is the drop's)."""
        self.attempt = 0
        """While it is down: the attempt under way (or the last), from 1."""
        self.attempt_since: float | None = None
        """When the attempt under way began (time.monotonic); None between attempts: one
        that hangs (ssh's 15 s, then a greeting's 30) is said as under way, not as the
        reason before it."""
        self.delay = first
        self._said = ""
        self._wake = asyncio.Event()

    def lost(self, down: str, reason: str, first: float | None = None) -> None:
        """The link dropped: attempts count from here, the first after `first` s (None:
        the reconnector's own)."""
        self.down, self.reason = down, reason
        # the drop's reason is said with the drop: an attempt failing alike is not news
        self.attempt, self.attempt_since, self._said = 0, None, reason
        self.delay = self.first if first is None else first

    async def next_attempt(self) -> None:
        """Waits the backoff (or until `now`), then counts the attempt that begins."""
        self.attempt_since = None
        self._wake.clear()
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(self._wake.wait(), self.delay)
        self.attempt, self.attempt_since = self.attempt + 1, time.monotonic()

    def failed(self, reason: str) -> bool:
        """The attempt under way failed with `reason`: the next waits twice as long. True
        when the reason is new (each said once, not at every try)."""
        self.reason = reason
        self.delay = min(self.delay * 2, self.most)
        new, self._said = reason != self._said, reason
        return new

    def back(self) -> None:
        """Reconnected (or given up): nothing is down."""
        self.down = self.reason = self.attempt_since = None

    def now(self) -> None:
        """The next attempt at once instead of after its backoff (on the loop's thread)."""
        self._wake.set()

    def trying_for(self, now: float | None = None) -> float | None:
        """Seconds the attempt under way has run; None between attempts."""
        if self.attempt_since is None:
            return None
        return (time.monotonic() if now is None else now) - self.attempt_since
