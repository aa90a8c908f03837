"""Respawn policy: whether a process that died comes back, and after how long (backoff)."""

from __future__ import annotations

import asyncio
import time

from ..events import Event
from ..process.readers import Running
from .stopping import Stopping


class Respawning(Stopping):
    """Bringing a crashed process back, with backoff."""

    def should_respawn(self, running: Running, code: int) -> bool:
        proc = running.plan
        if not proc.respawn or running.stopping or self.shutting_down or code == 0:
            return False  # a clean exit is a finished job, not a crash
        limit = proc.respawn_max_retries
        return limit < 0 or self.retries.get(proc.id, 0) < limit

    async def respawn(self, running: Running) -> None:
        proc = running.plan
        tries = self.retries[proc.id] = self.retries.get(proc.id, 0) + 1
        # back off while it dies at once, so a crash loop does not spin the machine; a run
        # that lasted starts the count again (a driver that fails once an hour for days
        # comes back after its own delay, not after the cap)
        quick = time.monotonic() - running.started < 2.0
        streak = self.quick_failures[proc.id] = (
            self.quick_failures.get(proc.id, 0) + 1 if quick else 0)
        delay = min(max(proc.respawn_delay, 0.1) * 2 ** min(max(streak - 1, 0), 16), 30.0)
        delay = max(delay, proc.respawn_delay)
        self.states[proc.id] = "respawning"
        self.busy += 1
        self.emit(Event("respawning", proc.id, reason=f"try {tries} in {delay:g} s"))
        try:
            await asyncio.sleep(delay)
        finally:
            self.busy -= 1
        if not self.shutting_down:
            await self.start(proc.id)
