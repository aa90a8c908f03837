"""Respawn policy: whether a process that died comes back, and after how long (backoff).

The `Respawner` owns the count of respawns and of quick failures in a row per process; it
decides, the supervisor waits and starts (`Starting.respawn`). Made and tested alone:
tests/integration/test_supervisor_parts.py.
"""

from __future__ import annotations

import time

from ...plan.model import ProcessPlan

QUICK = 2.0
"""A run shorter than this (seconds) is a quick failure: the next delay doubles."""
MAX_DELAY = 30.0
"""The backoff's cap (seconds), unless the file's own respawn_delay is longer."""


class Respawner:
    """The respawn policy and its backoff."""

    def __init__(self) -> None:
        self.retries: dict[str, int] = {}
        """Respawns of each process so far."""
        self.quick_failures: dict[str, int] = {}
        """Crashes in a row within `QUICK` s of starting, by process (respawn back-off)."""

    def wants(self, proc: ProcessPlan, code: int, requested: bool) -> bool:
        """Whether `proc`, which exited with `code`, comes back; `requested`: it was
        stopped by someone (a stop, the launch's shutdown), which never respawns.

        Any end counts, a clean exit too: launch's ExecuteLocal respawns whatever the
        return code (its docstring says "abnormally died", its code does not look), and a
        bringup written for ros2 launch counts on a node that exits 0 coming back."""
        if not proc.respawn or requested:
            return False
        limit = proc.respawn_max_retries
        return limit < 0 or self.retries.get(proc.id, 0) < limit

    def next_try(self, proc: ProcessPlan, started: float,
                 now: float | None = None) -> tuple[int, float]:
        """Counts one more respawn of `proc` (which had started at `started`, monotonic
        time); returns its number and the seconds to wait before it."""
        tries = self.retries[proc.id] = self.retries.get(proc.id, 0) + 1
        # back off while it dies at once, so a crash loop does not spin the machine; a run
        # that lasted starts the count again (a driver that fails once an hour for days
        # comes back after its own delay, not after the cap)
        quick = (time.monotonic() if now is None else now) - started < QUICK
        streak = self.quick_failures[proc.id] = (
            self.quick_failures.get(proc.id, 0) + 1 if quick else 0)
        delay = min(max(proc.respawn_delay, 0.1) * 2 ** min(max(streak - 1, 0), 16), MAX_DELAY)
        return tries, max(delay, proc.respawn_delay)

    def forget(self, process_id: str) -> None:
        """An operator stopped or started it: its next crash backs off from the file's own
        delay again, and its respawns are counted from zero."""
        self.retries.pop(process_id, None)
        self.quick_failures.pop(process_id, None)

    def tries(self, process_id: str) -> int:
        return self.retries.get(process_id, 0)
