"""Rate and bandwidth of topics, as `ros2 topic hz` and `ros2 topic bw` compute them.

Both take the times messages were *received* here: the rate is one over the mean period
between consecutive messages of the window; the bandwidth is the bytes of the window's
messages over the time from its first message to now. The window here is a time span
(`window_s`) rather than a message count, so a 1 Hz and a 1 kHz topic read alike.

`hz` on the command line keeps ros2's own window instead (`MessageWindow`: the last N
messages, with min, max and standard deviation of the periods, and ros2 topic bw's figures).

Subscriptions are generic (`raw=True`: serialized bytes, never deserialized, so measuring
costs little) with a reliability that matches the publishers', and always volatile: a
transient-local topic (/rosout, /tf_static, /robot_description, maps) would otherwise hand
the new subscription its publishers' kept history at once and inflate the rate. As with
`ros2 topic hz` (which subscribes with the volatile sensor-data profile), only what is
published after the subscription matched is counted.

Messages are not delivered by the bridge's executor: an executor callback costs about half a
millisecond of Python per message, a whole core for a 1 kHz topic, and falls behind it. Each
RateMeter has one thread waiting on its own wait set; on each wake-up it takes every message
waiting and records only when each was taken and its size.
"""

from __future__ import annotations

import asyncio
import os
import threading
import time
from collections import deque
from contextlib import ExitStack
from itertools import pairwise
from typing import Any

from rclpy.callback_groups import CallbackGroup

from ..calls import RosError
from ..messages import MessageError, import_type


def message_class(type_name: str) -> Any:
    """The Python class of a message type, or a one-line error saying what to install."""
    try:
        return import_type(type_name, "msg")
    except MessageError:
        package = type_name.split("/")[0]
        distro = os.environ.get("ROS_DISTRO", "jazzy")
        raise MessageError(f"{type_name}: install the Python package "
                           f"ros-{distro}-{package.replace('_', '-')}") from None


def matching_qos(publisher_profiles: list[Any], replay: bool = False) -> Any:
    """A subscriber QoS every publisher can talk to: best effort if any publisher is.
    `replay` (echo): transient local if all publishers are, so late-joining reads the kept
    messages too; otherwise volatile, so nothing published before it is counted."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

    qos = QoSProfile(depth=10)
    if any(p.reliability == ReliabilityPolicy.BEST_EFFORT for p in publisher_profiles):
        qos.reliability = ReliabilityPolicy.BEST_EFFORT
    if replay and publisher_profiles and all(p.durability == DurabilityPolicy.TRANSIENT_LOCAL
                                             for p in publisher_profiles):
        qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
    return qos


async def wait_for_publishers(node: Any, topic: str, timeout: float) -> list[Any]:
    """The topic's publishers' endpoint infos, once discovery has found at least one."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    while True:
        infos = await asyncio.to_thread(node.get_publishers_info_by_topic, topic)
        if infos:
            return list(infos)
        if loop.time() > deadline:
            raise RosError(f"topic {topic} has no publisher (waited {timeout:g} s)")
        await asyncio.sleep(0.1)


class RateWindow:
    """Receive times and sizes of one topic's messages over the last `window_s` seconds.

    Thread-safe: messages arrive on the meter's thread, reads come from asyncio."""

    def __init__(self, topic: str, window_s: float = 10.0) -> None:
        self.topic = topic
        self.window_s = window_s
        self.started = time.monotonic()
        self.samples: deque[tuple[float, int]] = deque()
        self.lock = threading.Lock()

    def add(self, size: int, now: float | None = None) -> None:
        now = time.monotonic() if now is None else now
        with self.lock:
            self.samples.append((now, size))
            self.trim(now)

    def add_many(self, samples: list[tuple[float, int]]) -> None:
        """(time taken, size) of messages, oldest first: one lock for a batch."""
        if not samples:
            return
        with self.lock:
            self.samples.extend(samples)
            self.trim(samples[-1][0])

    def trim(self, now: float) -> None:
        while self.samples and self.samples[0][0] < now - self.window_s:
            self.samples.popleft()

    def result(self, now: float | None = None) -> dict[str, Any]:
        """`{"topic", "rate_hz", "bytes_per_s", "messages", "window_s"}`; the rates are None
        until two messages arrived in the window; window_s is the span measured so far."""
        now = time.monotonic() if now is None else now
        with self.lock:
            self.trim(now)
            samples = list(self.samples)
        span = min(self.window_s, now - self.started)
        rate = bandwidth = None
        if len(samples) >= 2:
            first, last = samples[0][0], samples[-1][0]
            if last > first:
                rate = (len(samples) - 1) / (last - first)  # 1 / mean period
            if now > first:
                bandwidth = sum(size for _, size in samples) / (now - first)
        return {"topic": self.topic,
                "rate_hz": None if rate is None else round(rate, 3),
                "bytes_per_s": None if bandwidth is None else round(bandwidth, 1),
                "messages": len(samples), "window_s": round(span, 3)}


class MessageWindow:
    """The last `size` periods between messages (so `size + 1` receive times) and the
    messages' sizes, as `ros2 topic hz -w` and `ros2 topic bw` keep them. Thread-safe."""

    def __init__(self, topic: str, size: int = 10000) -> None:
        self.topic = topic
        self.size = size
        self.started = time.monotonic()
        self.samples: deque[tuple[float, int]] = deque(maxlen=size + 1)
        self.received = 0
        self.lock = threading.Lock()

    def add_many(self, samples: list[tuple[float, int]]) -> None:
        with self.lock:
            self.samples.extend(samples)
            self.received += len(samples)

    def result(self, now: float | None = None) -> dict[str, Any]:
        """ros2 topic hz's figures (`rate_hz`, `min_s`, `max_s`, `std_dev_s` of the periods,
        `window`: how many periods), ros2 topic bw's (`bytes_per_s` over the window's
        messages up to now, `size_mean`, `size_min`, `size_max`), `messages` received in
        all and `elapsed_s` since the measure began. None where there is too little."""
        now = time.monotonic() if now is None else now
        with self.lock:
            samples = list(self.samples)
            received = self.received
        periods = [b[0] - a[0] for a, b in pairwise(samples)]
        rate = low = high = deviation = None
        if periods:
            mean = sum(periods) / len(periods)
            rate = 1.0 / mean if mean > 0 else None
            low, high = min(periods), max(periods)
            deviation = (sum((p - mean) ** 2 for p in periods) / len(periods)) ** 0.5
        sizes = [size for _, size in samples]
        bandwidth = None
        if len(samples) >= 2 and now > samples[0][0]:
            bandwidth = sum(sizes) / (now - samples[0][0])
        return {"topic": self.topic, "rate_hz": rate, "min_s": low, "max_s": high,
                "std_dev_s": deviation, "window": len(periods), "messages": received,
                "bytes_per_s": bandwidth,
                "size_mean": sum(sizes) / len(sizes) if sizes else None,
                "size_min": min(sizes) if sizes else None,
                "size_max": max(sizes) if sizes else None,
                "elapsed_s": round(now - self.started, 3)}


class NotByExecutor(CallbackGroup):
    """A callback group whose entities no executor waits on or runs (Executor.can_execute
    asks the group): the subscriptions belong to the bridge's node, so they are made and
    destroyed like any other and hidden from the graph like it, but the meter's thread
    alone takes their messages."""

    def can_execute(self, entity: Any) -> bool:
        return False

    def beginning_execution(self, entity: Any) -> bool:
        return False

    def ending_execution(self, entity: Any) -> None:
        pass


IDLE_WAIT_NS = 500_000_000
"""How long the meter's thread waits at most: it notices a context shut down under it."""


class RateMeter:
    """Many topics measured at once on one node (the bridge's), started and stopped at will:
    the TUI measures only the topics on screen.

    Subscriptions are made and destroyed on the caller's thread. The meter's thread runs
    while any topic is measured; it holds each subscription's handle while it waits and
    takes, so rclpy defers destroying one in use until the thread lets go of it."""

    def __init__(self, node: Any) -> None:
        self.node = node
        self.windows: dict[str, RateWindow | MessageWindow] = {}
        self.subscriptions: dict[str, Any] = {}
        self.group = NotByExecutor()
        self.lock = threading.Lock()  # guards the two dicts and `changed` with the thread
        # the thread's wake-up when the topics change, None while no thread runs
        self.changed: Any = None
        self.thread: threading.Thread | None = None

    async def start(self, topic: str, window_s: float = 10.0, wait: float = 5.0,
                    messages: int | None = None) -> None:
        """Measures `topic` from now on (a no-op when it already is, bar a new window);
        `messages`: over the last N messages (MessageWindow) rather than `window_s`."""
        if topic in self.windows:
            self.set_window(topic, window_s)
            return
        infos = await wait_for_publishers(self.node, topic, wait)
        cls = message_class(infos[0].topic_type)
        if topic in self.windows:  # started by another caller while this one waited
            self.set_window(topic, window_s)
            return
        subscription = self.node.create_subscription(
            cls, topic, lambda _data: None, matching_qos([i.qos_profile for i in infos]),
            callback_group=self.group, raw=True)
        with self.lock:
            self.windows[topic] = RateWindow(topic, window_s) if messages is None else \
                MessageWindow(topic, messages)
            self.subscriptions[topic] = subscription
            if self.changed is None:
                self.start_thread()
            else:
                self.changed.trigger()

    def set_window(self, topic: str, window_s: float) -> None:
        window = self.windows[topic]
        if isinstance(window, RateWindow):
            window.window_s = window_s

    def start_thread(self) -> None:
        from rclpy.guard_condition import GuardCondition

        # made apart from the node: no executor waits on it
        changed = self.changed = GuardCondition(None, None, context=self.node.context)
        self.thread = threading.Thread(target=self.take_loop, args=(changed,), daemon=True,
                                       name="rate meter")
        self.thread.start()

    def stop(self, topic: str) -> None:
        """Stops measuring `topic`; its subscription goes as soon as the thread lets go."""
        with self.lock:
            subscription = self.subscriptions.pop(topic, None)
            self.windows.pop(topic, None)
            if subscription is not None and self.changed is not None:
                self.changed.trigger()
        if subscription is not None:
            self.node.destroy_subscription(subscription)

    def stop_all(self) -> None:
        for topic in list(self.subscriptions):
            self.stop(topic)

    def close(self, timeout: float = 5.0) -> None:
        """Before the node goes: every topic stopped and the thread ended. A thread still
        holding subscriptions would let go of them (and rclpy destroy them, deferred until
        then) after their node and context were gone: a segfault in the thread."""
        self.stop_all()
        if self.thread is not None:
            self.thread.join(timeout)

    def measured(self) -> list[str]:
        with self.lock:
            return sorted(self.windows)

    def read(self, topic: str | None = None) -> dict[str, dict[str, Any]]:
        """Results by topic: all measured topics, or only `topic`."""
        with self.lock:  # the thread forgets topics whose node was destroyed
            windows = dict(self.windows)
        topics = sorted(windows) if topic is None else [topic]
        return {t: windows[t].result() for t in topics if t in windows}

    # --- the meter's thread ----------------------------------------------------------------

    def take_loop(self, changed: Any) -> None:
        """Until no topic is left: wait for messages or a change, take all that wait."""
        from rclpy.exceptions import InvalidHandle
        from rclpy.impl.implementation_singleton import rclpy_implementation

        context = self.node.context
        while True:
            with self.lock:
                measured = [(self.subscriptions[t], self.windows[t]) for t in self.subscriptions]
                if not measured or not context.ok():
                    self.changed = None
                    break
            try:
                with ExitStack() as held:
                    for subscription, _ in measured:
                        held.enter_context(subscription.handle)
                    held.enter_context(changed.handle)
                    held.enter_context(context.handle)
                    wait_set = rclpy_implementation.WaitSet(len(measured), 1, 0, 0, 0, 0,
                                                            context.handle)
                    self.serve(wait_set, measured, changed)
            except InvalidHandle:  # stopped meanwhile (the next round has it not) or destroyed
                self.forget_destroyed()  # with the node: no round would ever have it
                continue
            except Exception:  # the context was shut down under the thread: nothing to do
                with self.lock:
                    self.changed = None
                break
        changed.destroy()

    def forget_destroyed(self) -> None:
        from rclpy.exceptions import InvalidHandle

        with self.lock:
            for topic, subscription in list(self.subscriptions.items()):
                try:
                    with subscription.handle:
                        pass
                except InvalidHandle:
                    del self.subscriptions[topic], self.windows[topic]

    def serve(self, wait_set: Any, measured: list[tuple[Any, RateWindow | MessageWindow]],
              changed: Any) -> None:
        """Waits and takes with this set of subscriptions until the set changes."""
        clock = time.monotonic
        while True:
            wait_set.clear_entities()
            for subscription, _ in measured:
                wait_set.add_subscription(subscription.handle)
            wait_set.add_guard_condition(changed.handle)
            wait_set.wait(IDLE_WAIT_NS)
            if wait_set.get_ready_entities("guard_condition"):
                return
            ready = wait_set.get_ready_entities("subscription")
            if not ready and not self.node.context.ok():
                return
            for subscription, window in measured:
                if subscription.handle.pointer not in ready:
                    continue
                handle, msg_type = subscription.handle, subscription.msg_type
                taken: list[tuple[float, int]] = []
                # each message's time is when it was taken: the wait set woke on the first
                while (message := handle.take_message(msg_type, True)) is not None:
                    taken.append((clock(), len(message[0])))
                window.add_many(taken)
