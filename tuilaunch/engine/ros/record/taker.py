"""The recorded topics' messages taken as published: serialized CDR bytes (generic
subscriptions, `raw=True`), never deserialized, each stamped with its arrival time and
handed to the sinks (the black box's tape, each recording's).

As RateMeter (../rates.py) does, the subscriptions belong to the bridge's node but no
executor runs them (`NotByExecutor`): one thread waits on a wait set of its own and takes
every message waiting; an executor callback per message would cost a core at a few kHz.
Subscriptions are made and destroyed on the caller's thread; the thread holds their handles
while it waits, so rclpy defers destroying one in use until it lets go.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from contextlib import ExitStack
from typing import Any

from ..graph.rates import IDLE_WAIT_NS, NotByExecutor

Sink = Callable[[str, int, bytes], None]
DEPTH = 100
"""Messages a subscription keeps while the thread is busy: a second of a 100 Hz topic."""


class Taker:
    """Topics subscribed at will; every message to `sink(topic, arrival_ns, data)`."""

    def __init__(self, node: Any, sink: Sink) -> None:
        from rclpy.guard_condition import GuardCondition

        self.node = node
        self.sink = sink
        self.group = NotByExecutor()
        self.subscriptions: dict[str, Any] = {}
        self.lock = threading.Lock()
        self.stopping = False
        self.changed = GuardCondition(None, None, context=node.context)
        self.thread = threading.Thread(target=self._loop, daemon=True, name="recorder")
        self.thread.start()

    def add(self, topic: str, message_class: Any, qos: Any) -> None:
        if topic in self.subscriptions:
            return
        qos.depth = DEPTH
        subscription = self.node.create_subscription(
            message_class, topic, lambda _data: None, qos, callback_group=self.group,
            raw=True)
        with self.lock:
            self.subscriptions[topic] = subscription
        self.changed.trigger()

    def topics(self) -> list[str]:
        with self.lock:
            return sorted(self.subscriptions)

    def close(self, timeout: float = 5.0) -> None:
        self.stopping = True
        try:
            self.changed.trigger()
        except Exception:  # the context is shut down: the thread ends by itself
            pass
        self.thread.join(timeout)
        with self.lock:
            subscriptions, self.subscriptions = list(self.subscriptions.values()), {}
        for subscription in subscriptions:
            self.node.destroy_subscription(subscription)

    # --- the taker's thread --------------------------------------------------------------------

    def _loop(self) -> None:
        from rclpy.impl.implementation_singleton import rclpy_implementation

        context = self.node.context
        try:
            while not self.stopping and context.ok():
                with self.lock:
                    taken = list(self.subscriptions.items())
                with ExitStack() as held:
                    for _, subscription in taken:
                        held.enter_context(subscription.handle)
                    held.enter_context(self.changed.handle)
                    held.enter_context(context.handle)
                    wait_set = rclpy_implementation.WaitSet(len(taken), 1, 0, 0, 0, 0,
                                                            context.handle)
                    self._serve(wait_set, taken)
        except Exception:  # the context was shut down under the thread: nothing to do
            pass
        finally:
            self.changed.destroy()

    def _serve(self, wait_set: Any, taken: list[tuple[str, Any]]) -> None:
        """Waits and takes with this set of subscriptions until it changes."""
        sink = self.sink
        while not self.stopping:
            wait_set.clear_entities()
            for _, subscription in taken:
                wait_set.add_subscription(subscription.handle)
            wait_set.add_guard_condition(self.changed.handle)
            wait_set.wait(IDLE_WAIT_NS)
            ready = wait_set.get_ready_entities("subscription")
            for topic, subscription in taken:
                if subscription.handle.pointer not in ready:
                    continue
                handle, msg_type = subscription.handle, subscription.msg_type
                while (message := handle.take_message(msg_type, True)) is not None:
                    sink(topic, time.time_ns(), message[0])
            if wait_set.get_ready_entities("guard_condition") or \
                    not self.node.context.ok():
                return


__all__ = ["Taker"]
