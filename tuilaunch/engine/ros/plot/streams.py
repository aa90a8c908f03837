"""`plot`, `plot_stop`, `plot_fields`: live plots of topic fields, one stream per client and
topic, fed by one sampler per topic (sampler.py) whatever the number of clients.

A stream is sent, every SEND_PERIOD, the buckets (buckets.py: min, max, last of each
1/20 s) closed since its last event, at most POINTS_PER_S a second per field whatever the
topic's rate; a new stream is first sent the buckets the sampler kept (up to 5 minutes, when
another client was plotting the topic already). A `raw` stream (`tuilaunch plot --csv`)
is sent every message's values instead: as many as the link carries (RAW_KEEP rows wait
for it, then the oldest are dropped and counted). A `stamp` stream's times are its
messages' header.stamp (where the type has one), not when they were received.

A client plots several topics with a stream each (their tags tell their events apart).

Streams end with `plot_stop`, their client (`client_gone`) or the session; the sampler of
a topic ends with its last stream.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from typing import Any

from ...errors import LaunchError
from ...run.events import PlotSamples
from ...run.plugins import Handlers
from ...run.vocabulary.ros_requests import PlotFields, PlotStart, PlotStop
from ..graph.stream_hooks import StreamHooks, in_background, stopped
from ..graph.topic_graph import topic_of
from ..ros_errors import RosError

SEND_PERIOD = 0.25
"""Seconds between a stream's events: four small events a second, a plot repaints no
faster."""
RAW_SEND_PERIOD = 0.1
"""Seconds between a raw stream's events (every message of them)."""
SAMPLE_WAIT = 1.0
"""Seconds `plot_fields` waits for a message whose sequences' lengths it lists (a topic
of joint states: `position[0..n]`); past it, the type's fields (a sequence's first)."""
DEPTH_SMALL, DEPTH_LARGE = 1000, 50
"""Messages the subscription keeps waiting for the sampler's thread: a second of a 1 kHz
topic of small messages (a busy machine's thread may wake late and
`--csv` misses none), a few of large or unbounded ones (a point cloud's)."""


@dataclass
class PlotStream:
    """What one client plots of one topic, and what it was sent."""

    fields: list[Any]  # FieldPath
    raw: bool
    tag: Any = None
    """The client's mark for this stream, in each of its events: events of the stream it
    replaced, still on their way, are told apart."""
    sent: dict[str, int] = field(default_factory=dict)
    """By field: the index of the last bucket sent."""
    stamp: bool = False
    """Times are the messages' header.stamp (the type has one)."""


class PlotStreams:
    """The running plot streams by (client, topic), and the samplers by topic."""

    def __init__(self, hooks: StreamHooks) -> None:
        self.hooks = hooks
        self.streams: dict[tuple[int, str], PlotStream] = {}
        self.samplers: dict[str, Any] = {}  # PlotSampler by topic
        self.task: asyncio.Task[None] | None = None
        self.lock = asyncio.Lock()  # one start or stop at a time: samplers are shared
        self.pending: set[asyncio.Task[None]] = set()

    async def _topic_type(self, topic: str, wait: float) -> tuple[Any, list[Any]]:
        """The topic's message class and its publishers' infos, once one publishes."""
        from ..graph.rates import message_class, wait_for_publishers

        bridge = await self.hooks.bridge()
        try:
            infos = await wait_for_publishers(bridge.node, topic, wait)
        except RosError:
            raise await self.hooks.no_publisher(bridge, topic, wait) from None
        return message_class(infos[0].topic_type), infos

    def handlers(self) -> Handlers:
        return {PlotStart: self.plot, PlotStop: self.plot_stop, PlotFields: self.plot_fields}

    async def plot_fields(self, request: PlotFields, client: int) -> dict[str, Any]:
        """`{"type", "fields", "stamped"}`: the topic's numeric fields by dotted path (the
        picker), each element of its sequences as a message received now has them."""
        from .fields import has_sequences, numeric_fields, stamp_reader, type_name

        topic = topic_of(request.topic)
        cls, infos = await self._topic_type(topic, self._wait(None))
        sample = None
        if has_sequences(cls):
            sample = await self._sample(topic, cls, infos)
        return {"type": type_name(cls), "fields": numeric_fields(cls, sample=sample),
                "stamped": stamp_reader(cls) is not None}

    async def _sample(self, topic: str, cls: Any, infos: list[Any]) -> Any:
        """The last message of `topic`: its plot's, else one waited for (SAMPLE_WAIT) on a
        sampler of its own; None when none came."""
        sampler: Any = self.samplers.get(topic)
        own = sampler is None
        if own:
            sampler = await self._new_sampler(topic, cls, infos)
        try:
            loop = asyncio.get_running_loop()
            deadline = loop.time() + SAMPLE_WAIT
            while sampler.last is None and loop.time() < deadline:
                await asyncio.sleep(0.05)
            return sampler.last
        finally:
            if own:
                await asyncio.to_thread(sampler.close)

    def _wait(self, asked: float | None) -> float:
        return min(asked or self.hooks.publisher_wait, self.hooks.publisher_wait)

    async def plot(self, request: PlotStart, client: int) -> dict[str, Any]:
        from .buckets import POINTS_PER_S
        from .fields import FieldError, compile_path, numeric_fields, type_name

        topic = topic_of(request.topic)
        if not self.hooks.subscribed(client):
            raise LaunchError("plot sends its points as events: subscribe first")
        paths = request.fields
        if not paths or not all(isinstance(p, str) for p in paths):
            raise ValueError("plot needs fields: a list of dotted paths (pose.position.x)")
        cls, infos = await self._topic_type(topic, self._wait(request.wait))
        try:
            fields = [compile_path(cls, path, topic) for path in dict.fromkeys(paths)]
        except FieldError as exc:
            raise LaunchError(str(exc)) from None
        async with self.lock:
            stream = PlotStream(fields, request.raw, request.tag)
            self.streams[(client, topic)] = stream
            sampler = await self._sampler(topic, cls, infos)
            stream.stamp = request.stamp and sampler.stamp_of is not None
            self._update(topic)
            if stream.raw:
                from .sampler import RawRows

                with sampler.lock:
                    sampler.raw[client] = RawRows(fields, stream.stamp)
            elif client in sampler.raw:
                with sampler.lock:
                    del sampler.raw[client]
        if self.task is None:
            self.task = asyncio.ensure_future(self._tick())
        return {"topic": topic, "type": type_name(cls), "fields": [f.path for f in fields],
                "numeric": numeric_fields(cls, sample=sampler.last),
                "stamped": sampler.stamp_of is not None, "stamp": stream.stamp,
                "points_per_s": POINTS_PER_S}

    async def _sampler(self, topic: str, cls: Any, infos: list[Any]) -> Any:
        sampler = self.samplers.get(topic)
        if sampler is None:
            sampler = self.samplers[topic] = await self._new_sampler(topic, cls, infos)
        return sampler

    async def _new_sampler(self, topic: str, cls: Any, infos: list[Any]) -> Any:
        from ..graph.rates import matching_qos
        from .fields import small
        from .sampler import PlotSampler

        bridge = await self.hooks.bridge()
        qos = matching_qos([i.qos_profile for i in infos])
        qos.depth = DEPTH_SMALL if small(cls) else DEPTH_LARGE
        return PlotSampler(bridge.node, topic, cls, qos)

    def _update(self, topic: str) -> None:
        """The sampler follows the union of the topic's streams' fields."""
        fields = {f.path: f for (_, t), s in self.streams.items() if t == topic
                  for f in s.fields}
        self.samplers[topic].set_fields(list(fields.values()))

    async def plot_stop(self, request: PlotStop, client: int) -> dict[str, Any]:
        await self._end(client, topic_of(request.topic))
        return {}

    async def _end(self, client: int, topic: str) -> None:
        async with self.lock:
            if self.streams.pop((client, topic), None) is None:
                return
            sampler = self.samplers[topic]
            with sampler.lock:
                sampler.raw.pop(client, None)
            if any(t == topic for _, t in self.streams):
                self._update(topic)
                return
            del self.samplers[topic]
        await asyncio.to_thread(sampler.close)

    def client_gone(self, client: int) -> None:
        for key in [k for k in self.streams if k[0] == client]:
            in_background(self.pending, self._end(*key))

    async def close(self) -> None:
        await stopped(self.task)
        self.task = None
        self.streams.clear()
        samplers, self.samplers = list(self.samplers.values()), {}
        for sampler in samplers:
            await asyncio.to_thread(sampler.close)

    # --- sending -----------------------------------------------------------------------------

    async def _tick(self) -> None:
        """Every RAW_SEND_PERIOD: raw streams their rows; every SEND_PERIOD the others
        their new buckets. Runs while any stream does."""
        loop = asyncio.get_running_loop()
        next_buckets = loop.time()
        try:
            while self.streams:
                await asyncio.sleep(RAW_SEND_PERIOD)
                buckets_now = loop.time() >= next_buckets
                if buckets_now:
                    next_buckets = loop.time() + SEND_PERIOD
                for (client, topic), stream in list(self.streams.items()):
                    sampler = self.samplers.get(topic)
                    if sampler is None:
                        continue
                    if stream.raw:
                        data = self._rows(sampler, client, stream)
                    elif buckets_now:
                        data = self._points(sampler, stream)
                    else:
                        continue
                    if data is not None:
                        self.hooks.send(PlotSamples(data=data), client)
        finally:
            self.task = None

    def _points(self, sampler: Any, stream: PlotStream) -> dict[str, Any] | None:
        import time

        now = time.time()
        fresh: dict[str, list[Any]] = {}
        with sampler.lock:
            kept = sampler.stamped if stream.stamp else sampler.buckets
            for field_path in stream.fields:
                buckets = kept.get(field_path.path)
                if buckets is None:
                    continue
                buckets.close_until(now)
                closed = buckets.since(stream.sent.get(field_path.path, -1))
                if closed:
                    stream.sent[field_path.path] = closed[-1].index
                    fresh[field_path.path] = closed
        if not fresh:
            return None
        # times as ms after a whole second: "t0" once, not a 14-digit time in each point
        since = int(min(closed[0].time for closed in fresh.values()))
        return {"topic": sampler.topic, "tag": stream.tag, "t0": since,
                "points": {path: [b.point(since) for b in closed]
                           for path, closed in fresh.items()}}

    def _rows(self, sampler: Any, client: int, stream: PlotStream) -> dict[str, Any] | None:
        with sampler.lock:
            rows = sampler.raw.get(client)
            if rows is None or not rows.rows:
                return None
            taken, rows.rows = list(rows.rows), type(rows.rows)(maxlen=rows.rows.maxlen)
            dropped, rows.dropped = rows.dropped, 0
        return {"topic": sampler.topic, "tag": stream.tag,
                "fields": [f.path for f in stream.fields],
                "rows": [[t, *(_exact(f.basic, v) for f, v in zip(stream.fields, values,
                                                                   strict=True))]
                         for t, values in taken],
                "dropped": dropped}


def _exact(basic: str, value: float | None) -> float | int | None:
    """A value as published: an integer as one, a 32-bit float as its shortest decimal
    (0.1, not 0.10000000149011612), a double as it is."""
    from .fields import INTEGERS

    if value is None or basic in ("double", "long double"):
        return value
    if basic in INTEGERS:
        return int(value)
    import numpy

    return float(str(numpy.float32(value)))
