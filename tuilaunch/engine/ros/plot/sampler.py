"""One topic's numeric fields, sampled as its messages are received, for the plots of every
client that plots it (streams.py).

As RateMeter (../rates.py) does, the subscription belongs to the bridge's node but no
executor runs it: a thread of its own waits on a wait set and takes every message waiting
(an executor callback costs a whole core at 1 kHz). Each message is deserialized by rclpy's
C code, its fields read, and its values folded into each field's buckets (buckets.py)
and appended to the rows of the clients that want every message (`tuilaunch plot --csv`).
A type with a header.stamp has each field folded twice, by arrival and by stamp: a plot
switches between the two times at once, with the minutes kept of both.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from contextlib import ExitStack
from typing import Any

from ..graph.rates import IDLE_WAIT_NS, NotByExecutor
from .buckets import FieldBuckets
from .fields import FieldPath, stamp_reader

RAW_KEEP = 200_000
"""Rows kept for a client that wants every message and has not been sent them yet: at
1 kHz, over three minutes of a link too slow for them; past it the oldest are dropped and
counted (the client says so)."""


class RawRows:
    """Every message's values of one client's fields, until sent: (time, values), the
    time its arrival or, with `stamp`, its header.stamp."""

    def __init__(self, fields: list[FieldPath], stamp: bool = False) -> None:
        self.fields = fields
        self.stamp = stamp
        self.rows: deque[tuple[float, list[float | None]]] = deque(maxlen=RAW_KEEP)
        self.dropped = 0


class PlotSampler:
    """The fields of one topic that some client plots, sampled on a thread of its own."""

    def __init__(self, node: Any, topic: str, message_class: Any, qos: Any) -> None:
        self.node = node
        self.topic = topic
        self.message_class = message_class
        self.lock = threading.Lock()
        self.fields: dict[str, FieldPath] = {}
        self.buckets: dict[str, FieldBuckets] = {}
        self.stamp_of = stamp_reader(message_class)
        """header.stamp in seconds, or None: the type has none."""
        self.stamped: dict[str, FieldBuckets] = {}
        """By field, the buckets by header.stamp (a type with one only)."""
        self.last: Any = None
        """The last message received (the field picker lists its sequences' elements)."""
        self.raw: dict[int, RawRows] = {}
        """By client: the rows of every message for the clients that want them."""
        self.received = 0
        self.group = NotByExecutor()
        self.subscription = node.create_subscription(
            message_class, topic, lambda _message: None, qos, callback_group=self.group)
        from rclpy.guard_condition import GuardCondition

        self.stopping = False
        self.wake = GuardCondition(None, None, context=node.context)
        self.thread = threading.Thread(target=self._loop, daemon=True,
                                       name=f"plot {topic}")
        self.thread.start()

    def set_fields(self, fields: list[FieldPath]) -> None:
        """The union of what the clients plot: a field new to it starts its buckets now;
        one no client plots any more is forgotten."""
        with self.lock:
            wanted = {f.path: f for f in fields}
            for path in list(self.fields):
                if path not in wanted:
                    del self.fields[path], self.buckets[path]
                    self.stamped.pop(path, None)
            for path, field in wanted.items():
                if path not in self.fields:
                    self.fields[path] = field
                    self.buckets[path] = FieldBuckets()
                    if self.stamp_of is not None:
                        self.stamped[path] = FieldBuckets()

    def close(self, timeout: float = 5.0) -> None:
        """The thread ended and the subscription destroyed (after the thread let go of
        its handle: destroyed under it, rclpy would defer it past the node's end)."""
        self.stopping = True
        try:
            self.wake.trigger()
        except Exception:  # the context is already shut down: the thread ends by itself
            pass
        self.thread.join(timeout)
        self.node.destroy_subscription(self.subscription)

    # --- the sampler's thread ------------------------------------------------------------------

    def _loop(self) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation

        context = self.node.context
        try:
            with ExitStack() as held:
                held.enter_context(self.subscription.handle)
                held.enter_context(self.wake.handle)
                held.enter_context(context.handle)
                wait_set = rclpy_implementation.WaitSet(1, 1, 0, 0, 0, 0, context.handle)
                while not self.stopping and context.ok():
                    wait_set.clear_entities()
                    wait_set.add_subscription(self.subscription.handle)
                    wait_set.add_guard_condition(self.wake.handle)
                    wait_set.wait(IDLE_WAIT_NS)
                    if wait_set.get_ready_entities("subscription"):
                        self._take()
        except Exception:  # the context was shut down under the thread: nothing to do
            pass
        finally:
            self.wake.destroy()

    def _take(self) -> None:
        handle, message_class = self.subscription.handle, self.message_class
        clock = time.time  # as received, in the server's clock: the same for every client
        stamp_of = self.stamp_of
        while (taken := handle.take_message(message_class, False)) is not None:
            now = clock()
            message = taken[0]
            stamp = now if stamp_of is None else stamp_of(message)
            with self.lock:
                self.received += 1
                self.last = message
                values: dict[str, float | None] = {}
                for path, field in self.fields.items():
                    value = values[path] = _value(field, message)
                    if value is not None:
                        self.buckets[path].add(now, value)
                        if stamp_of is not None:
                            self.stamped[path].add(stamp, value)
                for rows in self.raw.values():
                    if len(rows.rows) == RAW_KEEP:
                        rows.dropped += 1
                    rows.rows.append((stamp if rows.stamp else now,
                                      [values[f.path] if f.path in values
                                       else _value(f, message) for f in rows.fields]))


def _value(field: FieldPath, message: Any) -> float | None:
    try:
        return field.value(message)
    except (TypeError, ValueError, AttributeError):
        return None
