"""Reading a run's `<id>.log` files back: `<unix time> <stream> <line>` per line.

The session server hands out file sizes; a reader stops at those, so what it reads and the
events it receives afterwards neither overlap nor leave a gap.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class LogLine:
    time: float
    stream: str
    text: str


def parse(raw: str) -> LogLine | None:
    parts = raw.rstrip("\n").split(" ", 2)
    if len(parts) < 2:
        return None
    try:
        stamp = float(parts[0])
    except ValueError:
        return None
    return LogLine(stamp, parts[1], parts[2] if len(parts) > 2 else "")


def read_lines(path: Path, end: int | None = None, start: int = 0) -> Iterator[LogLine]:
    """Every line of a log file from byte `start` up to byte `end` (the whole file if None)."""
    try:
        handle = open(path, "rb")
    except OSError:
        return
    with handle:
        handle.seek(start)
        remaining = None if end is None else max(end - start, 0)
        while remaining is None or remaining > 0:
            raw = handle.readline() if remaining is None else handle.readline(remaining)
            if not raw or not raw.endswith(b"\n"):
                return  # a half-written last line is the next event's, not ours
            if remaining is not None:
                remaining -= len(raw)
            line = parse(raw.decode("utf-8", "replace"))
            if line is not None:
                yield line


def tail_lines(path: Path, end: int, count: int) -> list[LogLine]:
    """The last `count` lines before byte `end`, read backwards: a huge log costs only its
    tail."""
    if count <= 0 or end <= 0:
        return []
    try:
        handle = open(path, "rb")
    except OSError:
        return []
    with handle:
        block = 1 << 16
        position = end
        data = b""
        while position > 0 and data.count(b"\n") <= count:
            step = min(block, position)
            position -= step
            handle.seek(position)
            data = handle.read(step) + data
    if position > 0:
        data = data[data.index(b"\n") + 1:]  # the first line may be cut
    raws = data.split(b"\n")[:-1][-count:]
    lines = [parse(raw.decode("utf-8", "replace")) for raw in raws]
    return [line for line in lines if line is not None]


def log_size(path: Path) -> int:
    try:
        return os.path.getsize(path)
    except OSError:
        return 0
