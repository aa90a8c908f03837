"""CPU, memory and threads of a session's processes, for `status` and for the clients that
watch them (`watch_resources`): sampled on demand, and once a second only while a client
watches, so a session nobody looks at reads nothing from /proc.
"""

from __future__ import annotations

import asyncio
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from ..events import Event, Resources, Trend
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


HIDDEN = {"cpu_percent": None, "rss_bytes": None, "threads": None}
"""The figures of a process whose figures a watcher does not show."""
HISTORY = 300
"""Samples kept per process, one a second while a client watches: the last five minutes
the selected node's detail line draws (its "trend")."""
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
        self.shown: dict[int, set[str] | None] = {}  # whose figures each watcher shows
        self.last_data: dict[str, dict[str, Any]] = {}  # the last tick's figures
        self.last_sample: float | None = None
        self.task: asyncio.Task[None] | None = None
        self.history: dict[str, deque[tuple[Any, Any]]] = {}
        """(CPU%, RSS) a second of each process, kept while some client watches, so a
        client that asks for a process's trend gets the minutes before."""
        self.trend: dict[int, set[str]] = {}
        """The processes whose history each watcher draws: sent a sample a second."""

    def sample(self) -> dict[str, Usage]:
        self.last_sample = time.monotonic()
        return self.sampler.sample(self.roots())

    async def current(self) -> dict[str, Usage]:
        """Every running process's usage now, CPU% included."""
        if self.last_sample is None or time.monotonic() - self.last_sample > FRESH:
            self.sample()
            await asyncio.sleep(FIRST_INTERVAL)
        return self.sample()

    def watch_trend(self, client: int, processes: Iterable[str]) -> dict[str, list[Any]]:
        """From now on `client` is sent each tick's (CPU%, RSS) of these processes (an
        event "trend"); returned: what is kept of them, oldest first."""
        wanted = set(processes)
        if wanted:
            self.trend[client] = wanted
        else:
            self.trend.pop(client, None)
        return {p: [list(sample) for sample in self.history[p]] for p in sorted(wanted)
                if p in self.history}

    def watch(self, client: int, on: bool, shown: Iterable[str] | None = None) -> None:
        """`shown`: the processes whose figures the client shows (None: all); of the others
        it is sent only whether their memory keeps growing, the mark every row shows. A
        watcher that changes its `shown` is sent the figures it now lacks at the next tick,
        not all of them again."""
        if on:
            shown = None if shown is None else set(shown)
            changed = client in self.watchers and shown != self.shown.get(client)
            self.shown[client] = shown
            if client not in self.watchers:
                self.watchers.add(client)
                self.sent[client] = {}  # a new watch is told every figure first
            if changed and self.last_data:
                self._tell(client, self.last_data)  # the selected node's figures at once
            if self.task is None:
                self.task = asyncio.ensure_future(self._loop())
        else:
            self.forget(client)

    def forget(self, client: int) -> None:
        self.watchers.discard(client)
        self.sent.pop(client, None)
        self.shown.pop(client, None)
        self.trend.pop(client, None)
        if not self.watchers:
            self.history.clear()  # kept while some client watches, not for nobody
        if not self.watchers and self.task is not None:
            self.task.cancel()
            self.task = None

    async def _loop(self) -> None:
        self.sample()  # the first event already has an interval for its CPU%
        while self.watchers:
            await asyncio.sleep(WATCH_PERIOD)
            data = {process: shown_fields(usage_fields(usage))
                    for process, usage in self.sample().items()}
            self.last_data = data
            for process, fields in data.items():
                self.history.setdefault(process, deque(maxlen=HISTORY)).append(
                    (fields["cpu_percent"], fields["rss_bytes"]))
            for client in list(self.watchers):
                self._tell(client, data)
                trend = {p: [data[p]["cpu_percent"], data[p]["rss_bytes"]]
                         for p in sorted(self.trend.get(client, ())) if p in data}
                if trend:
                    self.send(Trend(data=trend), client)

    def _tell(self, client: int, data: dict[str, dict[str, Any]]) -> None:
        """Only the figures that moved (at the precision shown) of the processes it shows
        cross the link; a process that stopped is sent once with None figures."""
        shown = self.shown.get(client)
        view = {p: f if shown is None or p in shown else {**HIDDEN, "growing": f["growing"]}
                for p, f in data.items()}
        last = self.sent.get(client, {})

        def moved(process: str, key: str, value: Any) -> bool:
            before = last.get(process, {})
            if key in before:
                return bool(before[key] != value)  # None: no longer shown, said once
            return value is not None  # nothing to take back of a figure never sent

        changed = {p: {k: v for k, v in f.items() if moved(p, k, v)} for p, f in view.items()}
        changed = {p: f for p, f in changed.items() if f}
        changed.update({p: usage_fields(None) for p in last if p not in view})
        self.sent[client] = view
        if changed or not last:
            self.send(Resources(data=changed), client)

    def close(self) -> None:
        self.watchers.clear()
        self.history.clear()
        if self.task is not None:
            self.task.cancel()
            self.task = None


__all__ = ["ResourceWatch", "usage_fields"]
