"""`echo` and `echo_stop`: one throttled stream of a topic's messages per client and topic.

A stream sends at most `max_per_s` messages a second (the newest each time: a screen
shows what the topic says now), or every message with 0; `count` ends it after that many,
the last marked done. It ends with its client (`client_gone`), and with the session.
"""

from __future__ import annotations

import asyncio
from typing import Any

from ...errors import LaunchError
from ...run.events import Echo
from ...run.plugins import Handlers
from ...run.vocabulary.ros_requests import EchoStart, EchoStop
from ..ros_errors import RosError
from .stream_hooks import StreamHooks, stopped
from .topic_graph import topic_of

ECHO_DEFAULT_PER_S = 5.0
"""Messages a second an echo stream sends by default: what a screen can show."""
ECHO_UNTHROTTLED_POLL = 0.05
"""With no throttle (`max_per_s` 0), how often the kept messages are sent."""


class EchoStreams:
    """The running echo streams, by (client, topic)."""

    def __init__(self, hooks: StreamHooks) -> None:
        self.hooks = hooks
        self.streams: dict[tuple[int, str], asyncio.Task[None]] = {}

    def handlers(self) -> Handlers:
        return {EchoStart: self.echo, EchoStop: self.echo_stop}

    async def echo(self, request: EchoStart, client: int) -> dict[str, Any]:
        topic = topic_of(request.topic)
        if not self.hooks.subscribed(client):
            raise LaunchError("echo sends its messages as events: subscribe first")
        count = request.count
        if count is not None and count < 1:
            raise ValueError(f"count {count!r} is not a positive number")
        per_s = ECHO_DEFAULT_PER_S if request.max_per_s is None else request.max_per_s
        # `echo --timeout 3` waits 3 s for a publisher, not the usual 5
        wait = min(request.wait or self.hooks.publisher_wait, self.hooks.publisher_wait)
        bridge = await self.hooks.bridge()
        try:
            stream = await bridge.start_echo(topic, wait=wait)
        except RosError:
            raise await self.hooks.no_publisher(bridge, topic, wait) from None
        old = self.streams.pop((client, topic), None)
        if old is not None:
            old.cancel()
        self.streams[(client, topic)] = asyncio.ensure_future(
            self._stream(bridge, stream, client, count, per_s))
        return {}

    async def _stream(self, bridge: Any, stream: Any, client: int, count: int | None,
                      per_s: float) -> None:
        topic = stream.topic
        sent = 0
        period = 1.0 / per_s if per_s > 0 else ECHO_UNTHROTTLED_POLL
        try:
            while count is None or sent < count:
                await asyncio.sleep(period)
                texts = await asyncio.to_thread(take_texts, stream, per_s > 0)
                for text in texts[:None if count is None else count - sent]:
                    sent += 1
                    data: dict[str, Any] = {"topic": topic, "text": text}
                    if sent == count:
                        data["done"] = True
                    self.hooks.send(Echo(data=data), client)
        finally:
            await bridge.stop_echo(stream)
            if self.streams.get((client, topic)) is asyncio.current_task():
                del self.streams[(client, topic)]

    async def echo_stop(self, request: EchoStop, client: int) -> dict[str, Any]:
        task = self.streams.pop((client, topic_of(request.topic)), None)
        if task is not None:
            task.cancel()
        return {}

    def client_gone(self, client: int) -> None:
        for key in [k for k in self.streams if k[0] == client]:
            self.streams.pop(key).cancel()

    async def close(self) -> None:
        await stopped(*self.streams.values())
        self.streams.clear()


def take_texts(stream: Any, newest_only: bool) -> list[str]:
    """The stream's kept messages as YAML (in a worker thread: deserializing costs); when
    throttled, only the newest: a screen shows what the topic says now."""
    from .echo import message_yaml  # loads rclpy: only once a client echoes a topic

    messages = stream.take()
    if newest_only:
        messages = messages[-1:]
    return [message_yaml(m) for m in messages]
