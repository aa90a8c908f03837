"""`watch_qos`: the graph's QoS problems, checked where the nodes run and sent when they change.

A display marks the nodes of a publisher/subscriber pair that cannot talk. Asking for them
from the display meant a round trip every few seconds, over an ssh link too, for marks that
rarely change. Here the session server checks while any client watches, and a watcher is
sent the problems only when they differ from what it was last sent: at once when it starts
watching, then on each change. A check that fails (ROS is not up yet, a graph query timed
out) changes nothing: the marks stay as they were.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any

from ...errors import LaunchError
from ...run.events import Event, Qos
from ...run.plugins import Handlers
from ...run.vocabulary.ros_requests import WatchQos
from ..ros_errors import RosError
from .stream_hooks import stopped

QOS_PERIOD = 5.0
"""Seconds between two checks of the graph while a client watches."""

Problems = list[dict[str, Any]]
"""The topics that have QoS problems, as `topics {problems_only}` gives them."""


class QosWatch:
    """The watchers, the last problems each was sent, and the task that checks."""

    def __init__(self, check: Callable[[], Awaitable[Problems]],
                 send: Callable[[Event, int], None]) -> None:
        self._check = check
        self._send = send
        self._sent: dict[int, Problems | None] = {}
        """Each watching client, and the problems it was last sent (None: nothing yet)."""
        self._last: Problems | None = None  # the newest check's result
        self._task: asyncio.Task[None] | None = None

    def handlers(self) -> Handlers:
        return {WatchQos: self.watch}

    async def watch(self, request: WatchQos, client: int) -> dict[str, Any]:
        """The `watch_qos {on}` request of a subscribed client."""
        if not request.on:
            self._sent.pop(client, None)
            return {}
        self._sent.setdefault(client, None)
        if self._last is not None:
            self._tell(client, self._last)  # what is known now, without waiting a check
        if self._task is None or self._task.done():
            self._task = asyncio.ensure_future(self._run())
        return {}

    def client_gone(self, client: int) -> None:
        self._sent.pop(client, None)

    async def close(self) -> None:
        await stopped(self._task)
        self._sent.clear()

    async def _run(self) -> None:
        while self._sent:
            try:
                problems = await self._check()
            except (LaunchError, RosError):
                problems = None  # nothing known this time: the marks stay as they are
            if problems is not None:
                self._last = problems
                for client in list(self._sent):
                    self._tell(client, problems)
            await asyncio.sleep(QOS_PERIOD)
        self._last = None  # nobody watches: the next watcher waits for a fresh check

    def _tell(self, client: int, problems: Problems) -> None:
        if client in self._sent and self._sent[client] != problems:
            self._sent[client] = problems
            self._send(Qos(data={"topics": problems}), client)


__all__ = ["QOS_PERIOD", "QosWatch"]
