"""What is recorded, in memory, until written: the channels (a topic, its type, its schema
text and its publishers' QoS) and the messages (channel, arrival time, serialized bytes).

A `Tape` is bounded in bytes (and, for the black box, in seconds): the oldest messages are
dropped first and counted, a message counted at its size plus a small overhead, so a flood
of images stays within the bound as a flood of small messages does. It is filled from the
taker's thread and the server's loop, and read from the loop: one lock.

An output line becomes an `rcl_interfaces/msg/Log` (CDR, encoded here: no rclpy needed) on
the channel `/tuilaunch/output`: name the process id, level from the line's ROS prefix.
"""

from __future__ import annotations

import struct
import threading
from collections import deque
from dataclasses import dataclass

from ...run.vocabulary.reported_names import ROS_LOG_PREFIX
from ...run.vocabulary.text import strip_ansi

OUTPUT_TOPIC = "/tuilaunch/output"
LOG_TYPE = "rcl_interfaces/msg/Log"
OVERHEAD = 96
"""Bytes counted for each message besides its data: the tuple, the int, the bytes' header."""
LEVELS = {"DEBUG": 10, "INFO": 20, "WARN": 30, "WARNING": 30, "ERROR": 40, "FATAL": 50}
LAUNCH = "launch"
"""The name of the launch's own lines (process started, exited) on the output channel."""


@dataclass(frozen=True)
class Channel:
    topic: str
    type: str
    definition: str
    qos: str = ""
    """The publishers' QoS as rosbag2 writes `offered_qos_profiles` (YAML), "" unknown."""

    def to_dict(self) -> dict[str, str]:
        return {"topic": self.topic, "type": self.type, "definition": self.definition,
                "qos": self.qos}


Record = tuple[str, int, bytes]
"""(topic, arrival time in ns since the epoch, serialized message)."""


class Tape:
    """Channels and messages, the oldest dropped past `max_bytes` or `seconds`."""

    def __init__(self, max_bytes: int, seconds: float | None = None) -> None:
        self.max_bytes = max_bytes
        self.window_ns = None if seconds is None else int(seconds * 1e9)
        self.channels: dict[str, Channel] = {}
        self.records: deque[Record] = deque()
        self.size = 0
        self.dropped = 0
        self.lock = threading.Lock()
        self.added = threading.Event()  # set by each add: a waiting reader wakes

    def channel(self, channel: Channel) -> None:
        with self.lock:
            self.channels.setdefault(channel.topic, channel)

    def add(self, topic: str, time_ns: int, data: bytes) -> None:
        with self.lock:
            self.records.append((topic, time_ns, data))
            self.size += len(data) + OVERHEAD
            self._trim(time_ns)
        self.added.set()

    def _trim(self, now_ns: int) -> None:
        records = self.records
        oldest = None if self.window_ns is None else now_ns - self.window_ns
        while records and (self.size > self.max_bytes or
                           (oldest is not None and records[0][1] < oldest)):
            _, _, data = records.popleft()
            self.size -= len(data) + OVERHEAD
            self.dropped += 1

    def take(self, max_bytes: int) -> tuple[list[Record], int]:
        """The oldest messages up to about `max_bytes` (at least one), removed; and the
        count dropped since the last take."""
        taken: list[Record] = []
        with self.lock:
            size = 0
            while self.records and (not taken or size < max_bytes):
                record = self.records.popleft()
                size += len(record[2]) + OVERHEAD
                taken.append(record)
            self.size -= size
            dropped, self.dropped = self.dropped, 0
            if not self.records:
                self.added.clear()
        return taken, dropped

    def snapshot(self, now_ns: int) -> tuple[list[Channel], list[Record]]:
        """The channels and the messages kept now (the window trimmed to `now_ns`), left in
        place: the black box goes on recording while its file is written."""
        with self.lock:
            self._trim(now_ns)
            return list(self.channels.values()), list(self.records)


def log_level(text: str, stream: str | None) -> int:
    """A line's level as rcl_interfaces/msg/Log says it: from its ROS prefix, else INFO on
    stdout and WARN on stderr (a traceback), as the TUI shows them."""
    match = ROS_LOG_PREFIX.match(text)
    if match:
        return LEVELS[match.group(1)]
    return LEVELS["WARN"] if stream == "stderr" else LEVELS["INFO"]


def log_message(time_ns: int, level: int, name: str, text: str) -> bytes:
    """An `rcl_interfaces/msg/Log` serialized as CDR (little endian), as rclpy would."""
    out = bytearray(b"\x00\x01\x00\x00")  # encapsulation: CDR, little endian

    def align(n: int) -> None:
        out.extend(b"\x00" * (-(len(out) - 4) % n))

    def string(value: str) -> None:
        raw = value.encode("utf-8", "replace") + b"\x00"
        align(4)
        out.extend(struct.pack("<I", len(raw)))
        out.extend(raw)

    sec, nanosec = divmod(time_ns, 1_000_000_000)
    out.extend(struct.pack("<iIB", sec, nanosec, level))
    string(name)
    string(text)
    string("")  # file
    string("")  # function
    align(4)
    out.extend(struct.pack("<I", 0))  # line
    return bytes(out)


def line_message(time_ns: int, name: str, line: str, stream: str | None) -> bytes:
    text = strip_ansi(line)
    return log_message(time_ns, log_level(text, stream), name, text)


__all__ = ["LAUNCH", "LOG_TYPE", "OUTPUT_TOPIC", "Channel", "Record", "Tape", "line_message",
           "log_message"]
