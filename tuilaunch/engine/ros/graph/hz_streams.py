"""`hz`, `hz_watch` and `hz_read`: a topic's rate measured for one client.

`hz` measures once over a window and answers; `hz_watch` (`tuilaunch hz`) measures over the
last messages and sends the figures as "hz" events until the client leaves or asks again.
Each client has its own meter: a client watching the same topic keeps its own window.
"""

from __future__ import annotations

import asyncio
from typing import Any

from ...errors import LaunchError
from ...run.events import Hz
from ...run.plugins import Handlers
from ...run.vocabulary.ros_requests import HzMeasure, HzRead, HzWatch
from ..ros_errors import RosError
from .stream_hooks import StreamHooks, stopped
from .topic_graph import topic_of

MAX_WINDOW = 600.0
"""The longest window `hz` measures over, in seconds."""


class HzStreams:
    """The `tuilaunch hz` clients' measures, by (client, topic): the task sending the
    figures, and the meter."""

    def __init__(self, hooks: StreamHooks) -> None:
        self.hooks = hooks
        self.streams: dict[tuple[int, str], tuple[asyncio.Task[None], Any]] = {}

    def handlers(self) -> Handlers:
        return {HzMeasure: self.hz, HzWatch: self.hz_watch, HzRead: self.hz_read}

    async def _meter(self, topic: str, **how: Any) -> Any:
        """A meter of its own measuring `topic`, once it has a publisher."""
        from .rates import RateMeter

        bridge = await self.hooks.bridge()
        meter = RateMeter(bridge.node)
        try:
            await meter.start(topic, wait=self.hooks.publisher_wait, **how)
        except RosError:
            meter.stop_all()
            raise await self.hooks.no_publisher(bridge, topic,
                                                self.hooks.publisher_wait) from None
        return meter

    async def hz(self, request: HzMeasure, client: int) -> dict[str, Any]:
        topic = topic_of(request.topic)
        window = request.window or 10.0
        if not 0 < window <= MAX_WINDOW:
            raise ValueError(f"window {window:g} s is out of range (0-{MAX_WINDOW:g} s)")
        meter = await self._meter(topic, window_s=window)
        try:
            await asyncio.sleep(window)
            result: dict[str, Any] = meter.read(topic)[topic]
            return result
        finally:
            meter.stop_all()

    async def hz_watch(self, request: HzWatch, client: int) -> dict[str, Any]:
        """The topic measured over its last `messages` messages (as ros2 topic hz -w), its
        figures sent to the client as an "hz" event every `every` s until it leaves;
        `hz_read` gives them at once."""
        topic = topic_of(request.topic)
        if not self.hooks.subscribed(client):
            raise LaunchError("hz sends its figures as events: subscribe first")
        messages = request.messages
        if messages < 1:
            raise ValueError(f"messages {messages!r} is not a positive number")
        meter = await self._meter(topic, messages=messages)
        old = self.streams.pop((client, topic), None)
        if old is not None:
            old[0].cancel()
        task = asyncio.ensure_future(self._stream(meter, topic, client, request.every or 1.0))
        self.streams[(client, topic)] = (task, meter)
        return {}

    async def _stream(self, meter: Any, topic: str, client: int, every: float) -> None:
        try:
            while True:
                await asyncio.sleep(every)
                for result in meter.read(topic).values():
                    self.hooks.send(Hz(data=result), client)
        finally:
            meter.stop_all()
            entry = self.streams.get((client, topic))
            if entry is not None and entry[0] is asyncio.current_task():
                del self.streams[(client, topic)]

    async def hz_read(self, request: HzRead, client: int) -> dict[str, Any]:
        topic = topic_of(request.topic)
        entry = self.streams.get((client, topic))
        if entry is None:
            raise LaunchError(f"{topic} is not measured for this client")
        result: dict[str, Any] = entry[1].read(topic)[topic]
        return result

    def client_gone(self, client: int) -> None:
        for key in [k for k in self.streams if k[0] == client]:
            self.streams.pop(key)[0].cancel()

    async def close(self) -> None:
        await stopped(*(task for task, _ in self.streams.values()))
        self.streams.clear()
