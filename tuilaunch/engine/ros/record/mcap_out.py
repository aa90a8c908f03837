"""An MCAP file as rosbag2's MCAP storage writes one (profile `ros2`): a schema per type
(encoding `ros2msg`, its full definition text), a channel per topic (message encoding
`cdr`, metadata `offered_qos_profiles`), each message's bytes as published with its arrival
as log and publish time, chunks compressed with zstd, and the summary (statistics, indexes)
written by `close`: Foxglove, `ros2 bag info`/`play` and PlotJuggler open it.

A file is never overwritten: `open_new` takes the first free name of `stem`, `stem-2`, ...
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from .tape import Channel, Record

LIBRARY = "tuilaunch"


def qos_yaml(profiles: list[Any]) -> str:
    """`offered_qos_profiles` as rosbag2 writes it, from the publishers' rclpy QoSProfiles."""
    out = []
    for p in profiles:
        def duration(d: Any) -> str:
            ns = int(getattr(d, "nanoseconds", 0))
            if ns <= 0 or ns >= 2**63 - 1:  # unset or infinite, as rmw says either
                return "\n    sec: 2147483647\n    nsec: 4294967295"
            return f"\n    sec: {ns // 10**9}\n    nsec: {ns % 10**9}"
        out.append(f"- history: {int(p.history)}\n  depth: {int(p.depth)}\n"
                   f"  reliability: {int(p.reliability)}\n  durability: {int(p.durability)}\n"
                   f"  deadline:{duration(p.deadline)}\n  lifespan:{duration(p.lifespan)}\n"
                   f"  liveliness: {int(p.liveliness)}\n"
                   f"  liveliness_lease_duration:{duration(p.liveliness_lease_duration)}\n"
                   f"  avoid_ros_namespace_conventions: false")
    return "\n".join(out)


def open_new(folder: Path, stem: str) -> tuple[Path, Any]:
    """The first free `stem.mcap`, `stem-2.mcap`, ... in `folder`, created (O_EXCL) and
    open for writing: two writers never share a name, no file is overwritten."""
    folder.mkdir(parents=True, exist_ok=True)
    for n in range(1, 10_000):
        path = folder / (f"{stem}.mcap" if n == 1 else f"{stem}-{n}.mcap")
        try:
            return path, open(path, "xb")
        except FileExistsError:
            continue
    raise FileExistsError(f"no free file name {stem}-N.mcap in {folder}")


def open_exact(path: Path) -> Any:
    """`-o FILE`: that file, refused when it exists (never overwritten)."""
    try:
        return open(path, "xb")
    except FileExistsError:
        raise FileExistsError(f"{path} exists: tuilaunch never overwrites a recording "
                              "(choose another -o)") from None


class McapOut:
    """One MCAP file being written: channels registered on first use."""

    def __init__(self, stream: Any, path: Path | str) -> None:
        from mcap.writer import CompressionType, Writer

        self.path = Path(path)
        self.stream = stream
        self.writer = Writer(stream, compression=CompressionType.ZSTD)
        self.writer.start(profile="ros2", library=LIBRARY)
        self.schemas: dict[str, int] = {}
        self.channels: dict[str, int] = {}
        self.known: dict[str, Channel] = {}
        self.messages = 0
        self.sequence = 0

    def channel(self, channel: Channel) -> None:
        """Registered now: in the file even when no message comes on it."""
        if channel.topic not in self.known:
            self.known[channel.topic] = channel
            self._channel_id(channel.topic)

    def _channel_id(self, topic: str) -> int | None:
        channel_id = self.channels.get(topic)
        if channel_id is not None:
            return channel_id
        channel = self.known.get(topic)
        if channel is None:
            return None
        schema_id = self.schemas.get(channel.type)
        if schema_id is None:
            schema_id = self.schemas[channel.type] = self.writer.register_schema(
                name=channel.type, encoding="ros2msg", data=channel.definition.encode())
        channel_id = self.channels[topic] = self.writer.register_channel(
            topic=topic, message_encoding="cdr", schema_id=schema_id,
            metadata={"offered_qos_profiles": channel.qos})
        return channel_id

    def add(self, records: list[Record]) -> None:
        for topic, time_ns, data in records:
            channel_id = self._channel_id(topic)
            if channel_id is None:
                continue
            self.sequence += 1
            self.writer.add_message(channel_id=channel_id, log_time=time_ns, data=data,
                                    publish_time=time_ns, sequence=self.sequence)
            self.messages += 1

    def size(self) -> int:
        """Bytes written so far (chunks are written as they fill)."""
        try:
            return int(self.stream.tell())
        except (OSError, ValueError):
            return 0

    def close(self) -> None:
        """The summary written (statistics, indexes): a complete file."""
        try:
            self.writer.finish()
        finally:
            self.stream.flush()
            os.fsync(self.stream.fileno())
            self.stream.close()


def write_file(folder: Path, stem: str, channels: list[Channel],
               records: list[Record]) -> tuple[Path, int]:
    """A whole file at once (the black box): its path and its number of messages."""
    path, stream = open_new(folder, stem)
    out = McapOut(stream, path)
    try:
        for channel in channels:
            out.channel(channel)
        out.add(records)
    finally:
        out.close()
    return path, out.messages


__all__ = ["McapOut", "open_exact", "open_new", "qos_yaml", "write_file"]
