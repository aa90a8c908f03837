"""CPU, memory and threads of a session's processes, for `status` and for the clients that
watch them (`watch_resources`): sampled on demand, and once a second only while a client
watches, so a session nobody looks at reads nothing from /proc.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable, Mapping
from typing import Any

from ..events import Event
from .resources import ResourceSampler, Usage

WATCH_PERIOD = 1.0
"""Seconds between `resources` events while a client watches."""
FIRST_INTERVAL = 0.3
"""A `status` with no recent sample samples twice this far apart: CPU% needs an interval
(0.3 s is 30 clock ticks, a 3 % resolution; enough to tell a busy node from an idle one)."""
FRESH = 5.0
"""A previous sample younger than this gives `status` its interval (a watcher's, usually)."""

Send = Callable[[Event, int], None]
"""Sends an event to one client by id."""


def usage_fields(usage: Usage | None) -> dict[str, Any]:
    """A process's fields in `status` and in `resources` events (None: not running)."""
    if usage is None:
        return {"cpu_percent": None, "rss_bytes": None, "threads": None, "growing": False}
    return {"cpu_percent": usage.cpu_percent, "rss_bytes": usage.rss_bytes,
            "threads": usage.threads, "growing": usage.memory_growing}


RSS_STEP = 64 << 10
"""Watchers get memory to this step: a display shows tenths of a MB at most, and a figure
that does not move is a repeat the ssh link's compression sends for almost nothing."""


def shown_fields(fields: dict[str, Any]) -> dict[str, Any]:
    """A sample as a display shows it: CPU in whole percent, memory to RSS_STEP."""
    cpu, rss = fields.get("cpu_percent"), fields.get("rss_bytes")
    if isinstance(cpu, float):
        fields["cpu_percent"] = float(round(cpu))
    if isinstance(rss, int):
        fields["rss_bytes"] = round(rss / RSS_STEP) * RSS_STEP
    return fields


class ResourceWatch:
    """Samples the process trees `roots()` names (`{process id: pid}` of running processes)
    when asked, and for watching clients once a second."""

    def __init__(self, roots: Callable[[], Mapping[str, int]], send: Send) -> None:
        self.roots = roots
        self.send = send
        self.sampler = ResourceSampler()
        self.watchers: set[int] = set()
        self.sent: dict[int, dict[str, Any]] = {}  # what each watcher was last told
        self.last_sample: float | None = None
        self.task: asyncio.Task[None] | None = None

    def sample(self) -> dict[str, Usage]:
        self.last_sample = time.monotonic()
        return self.sampler.sample(self.roots())

    async def current(self) -> dict[str, Usage]:
        """Every running process's usage now, CPU% included."""
        if self.last_sample is None or time.monotonic() - self.last_sample > FRESH:
            self.sample()
            await asyncio.sleep(FIRST_INTERVAL)
        return self.sample()

    def watch(self, client: int, on: bool) -> None:
        if on:
            self.watchers.add(client)
            self.sent[client] = {}  # a new watch is told every figure first
            if self.task is None:
                self.task = asyncio.ensure_future(self._loop())
        else:
            self.forget(client)

    def forget(self, client: int) -> None:
        self.watchers.discard(client)
        self.sent.pop(client, None)
        if not self.watchers and self.task is not None:
            self.task.cancel()
            self.task = None

    async def _loop(self) -> None:
        self.sample()  # the first event already has an interval for its CPU%
        while self.watchers:
            await asyncio.sleep(WATCH_PERIOD)
            data = {process: shown_fields(usage_fields(usage))
                    for process, usage in self.sample().items()}
            for client in list(self.watchers):
                # only the figures that moved (at the precision shown) cross the link; a
                # process that stopped is sent once with None figures
                last = self.sent.get(client, {})
                changed = {p: {k: v for k, v in f.items() if last.get(p, {}).get(k, v) != v
                               or p not in last} for p, f in data.items() if last.get(p) != f}
                changed.update({p: usage_fields(None) for p in last if p not in data})
                self.sent[client] = data
                if changed or not last:
                    self.send(Event("resources", data=changed), client)

    def close(self) -> None:
        self.watchers.clear()
        if self.task is not None:
            self.task.cancel()
            self.task = None


__all__ = ["ResourceWatch", "usage_fields"]
