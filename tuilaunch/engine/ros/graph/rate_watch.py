"""`watch_rates`: live rates of the topics each client watches (the Topics tab's rows on
screen), one `rates` event a second.

The union of what the clients watch is measured, no more: a topic nobody watches any
longer is stopped. Each watched topic keeps its last minutes of rates, sent to a client
that starts watching it; a topic that cannot be measured yet (no publisher, a type not
installed) is said so, and tried again each second.
"""

from __future__ import annotations

import asyncio
from collections import deque
from collections.abc import Callable
from typing import Any

from ...run.events import Rates
from ...run.plugins import Handlers
from ...run.vocabulary.ros_requests import WatchRates
from ..ros_errors import RosError
from .stream_hooks import StreamHooks, in_background, stopped

RATES_PERIOD = 1.0
"""Seconds between `rates` events to a watching client."""
RATE_HISTORY = 300
"""Rates kept per watched topic, one a second: the Topics tab's last five minutes."""


class RateWatch:
    def __init__(self, hooks: StreamHooks, made: Callable[[], Any]) -> None:
        """`made()`: the launch's bridge if one was made, else None (a watch that ends does
        not make one to stop nothing)."""
        self.hooks = hooks
        self._made = made
        self.watching: dict[int, set[str]] = {}
        self.unmeasured: dict[str, str] = {}  # watched topics not measured yet: why
        self.history: dict[str, deque[float | None]] = {}
        """A rate a second of each topic some client watches, for as long as one does: a
        client that starts watching it is sent the minutes before (`watch_rates`)."""
        self.task: asyncio.Task[None] | None = None
        self.pending: set[asyncio.Task[None]] = set()

    def handlers(self) -> Handlers:
        return {WatchRates: self.watch_rates}

    async def watch_rates(self, request: WatchRates, client: int) -> dict[str, Any]:
        topics = request.topics
        if not all(isinstance(t, str) for t in topics):
            raise ValueError("watch_rates needs topics as a list of names")
        if topics:
            self.watching[client] = set(topics)
        else:
            self.watching.pop(client, None)
        await self.update()
        return {"unmeasured": {t: self.unmeasured[t] for t in topics if t in self.unmeasured},
                "history": {t: list(self.history[t]) for t in topics if t in self.history}}

    def wanted(self) -> set[str]:
        return set().union(*self.watching.values()) if self.watching else set()

    async def update(self) -> None:
        """Measures the union of the watched topics, no more; the ticker runs while any
        client watches."""
        wanted = self.wanted()
        for kept in (self.unmeasured, self.history):
            for topic in [t for t in kept if t not in wanted]:
                del kept[topic]
        if not wanted:
            if self.task is not None:
                self.task.cancel()
                self.task = None
            if self._made() is not None:
                await self._made().stop_rates()
            return
        bridge = await self.hooks.bridge()
        measured = set(bridge.rate_meter().measured())
        await bridge.stop_rates(sorted(measured - wanted))
        await self._start_missing(bridge, wanted - measured)
        if self.task is None:
            self.task = asyncio.ensure_future(self._tick())

    async def _start_missing(self, bridge: Any, topics: set[str]) -> None:
        from ..messages import MessageError

        for topic in sorted(topics):
            try:
                await bridge.start_rates([topic], wait=0.0)
                self.unmeasured.pop(topic, None)
            except RosError:
                self.unmeasured[topic] = await self.hooks.problem(bridge, topic)
            except MessageError as exc:
                self.unmeasured[topic] = str(exc)

    async def _tick(self) -> None:
        while self.watching:
            await asyncio.sleep(RATES_PERIOD)
            bridge = self._made()
            if bridge is None:
                continue
            if self.unmeasured:  # a publisher may have come since
                await self._start_missing(bridge, set(self.unmeasured))
            rates = await bridge.read_rates()
            for topic in self.wanted():
                self.history.setdefault(topic, deque(maxlen=RATE_HISTORY)).append(
                    rates.get(topic, {}).get("rate_hz"))
            for client, topics in list(self.watching.items()):
                data = {t: {"rate_hz": rates.get(t, {}).get("rate_hz"),
                            "bytes_per_s": rates.get(t, {}).get("bytes_per_s")}
                        for t in sorted(topics)}
                self.hooks.send(Rates(data=data), client)

    def client_gone(self, client: int) -> None:
        if self.watching.pop(client, None) is not None:
            in_background(self.pending, self.update())

    async def close(self) -> None:
        await stopped(self.task)
        self.watching.clear()
        bridge = self._made()
        if bridge is not None:
            await bridge.stop_rates()
