"""Messages as `ros2 topic echo` prints them: YAML, `---` after each message, long arrays
and strings cut (its `--truncate-length`, default 128) with a count of what was left out;
and a throttle so a screen shows at most a few messages a second of a 1 kHz topic.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from typing import Any

import yaml

from ..messages import to_plain
from .rates import matching_qos, message_class, wait_for_publishers

TRUNCATE_LENGTH = 128


def truncated(value: Any, length: int = TRUNCATE_LENGTH) -> Any:
    """A plain message value with sequences and strings longer than `length` cut."""
    if isinstance(value, dict):
        return {k: truncated(v, length) for k, v in value.items()}
    if isinstance(value, list):
        kept = [truncated(v, length) for v in value[:length]]
        if len(value) > length:
            kept.append(f"... ({len(value)} items)")
        return kept
    if isinstance(value, str) and len(value) > length:
        return value[:length] + f"... ({len(value)} characters)"
    return value


def message_yaml(message: Any, truncate_length: int | None = TRUNCATE_LENGTH) -> str:
    """One message as YAML followed by `---`, as `ros2 topic echo` prints it."""
    plain = to_plain(message)
    if truncate_length is not None:
        plain = truncated(plain, truncate_length)
    if not isinstance(plain, dict):
        plain = {"data": plain}
    text = yaml.safe_dump(plain, default_flow_style=False, sort_keys=False,
                          allow_unicode=True, width=1 << 16)
    return text + "---\n"


class Throttle:
    """Lets through at most `per_second` events; `ready()` says whether this one may pass."""

    def __init__(self, per_second: float = 5.0) -> None:
        self.period = 1.0 / per_second if per_second > 0 else 0.0
        self.last: float | None = None

    def ready(self, now: float | None = None) -> bool:
        now = time.monotonic() if now is None else now
        if self.last is not None and now - self.last < self.period:
            return False
        self.last = now
        return True


class EchoSubscription:
    """The latest messages of one topic, kept (at most `keep`) until taken.

    Kept serialized, and deserialized only when taken: a screen shows a few messages a
    second, and deserializing every message of a 30 Hz point cloud in Python would cost far
    more than receiving it. Messages arrive on the bridge's executor threads; `take()` is
    for any other thread."""

    def __init__(self, topic: str, message_type: Any, keep: int = 100) -> None:
        self.topic = topic
        self.message_type = message_type
        self.messages: deque[bytes] = deque(maxlen=keep)
        self.received = 0
        self.lock = threading.Lock()
        self.subscription: Any = None

    def add(self, data: bytes) -> None:
        with self.lock:
            self.messages.append(data)
            self.received += 1

    def take(self) -> list[Any]:
        """The messages kept since the last take, oldest first."""
        from rclpy.serialization import deserialize_message

        with self.lock:
            taken = list(self.messages)
            self.messages.clear()
        return [deserialize_message(data, self.message_type) for data in taken]

    def take_yaml(self, truncate_length: int | None = TRUNCATE_LENGTH) -> str:
        return "".join(message_yaml(m, truncate_length) for m in self.take())


async def start_echo(node: Any, topic: str, wait: float = 5.0, keep: int = 100)\
        -> EchoSubscription:
    """Subscribes `node` to `topic` (QoS matching its publishers); stop with `stop_echo`."""
    infos = await wait_for_publishers(node, topic, wait)
    cls = message_class(infos[0].topic_type)
    echo = EchoSubscription(topic, cls, keep)
    echo.subscription = node.create_subscription(
        cls, topic, echo.add, matching_qos([i.qos_profile for i in infos], replay=True),
        raw=True)
    return echo


def stop_echo(node: Any, echo: EchoSubscription) -> None:
    if echo.subscription is not None:
        node.destroy_subscription(echo.subscription)
        echo.subscription = None
