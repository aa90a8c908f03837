"""Reading a run's `<id>.log` files back: `<unix time> <stream> <line>` per line.

The session server hands out file sizes; a reader stops at those, so what it reads and the
events it receives afterwards neither overlap nor leave a gap.
"""

from __future__ import annotations

import collections
import os
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from ..events import Event, ExitCause, ProcessExited, event_of
from .protocol import MESSAGE_TEXT

LAUNCH_LOG = "@launch"
"""What `read_log` takes, instead of a process id, for launch.log: every event but output,
`<time> <kind> <process> pid=.. code=.. requested=1 level=.. reason=..` (supervisor/core.py)."""
LIFE_KINDS = ("started", "exited", "failed", "respawning", "log", "lifecycle", "component")
"""The events of a process's life that `tuilaunch logs` tells among its lines."""
_DETAIL = re.compile(r"(pid|code|requested|level)=(\S*)\s*")
_SAID = re.compile(r"^\[([A-Z]+)\] \[([^\]]+)\]: (.*)$", re.DOTALL)


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


def tail_lines(path: Path, end: int, count: int,
               budget: int | None = None) -> list[LogLine]:
    """The last `count` lines before byte `end`, read backwards: a huge log costs only its
    tail. `budget`: no more than that many bytes of them (at least the last line)."""
    if count <= 0 or end <= 0:
        return []
    try:
        handle = open(path, "rb")
    except OSError:
        return []
    blocks: list[bytes] = []  # joined once: a long line is read in blocks, not copied in each
    newlines = 0
    with handle:
        block = 1 << 16
        position = end
        while position > 0 and newlines <= count:
            if budget is not None and end - position > budget and newlines > 1:
                break
            step = min(block, position)
            position -= step
            handle.seek(position)
            blocks.append(handle.read(step))
            newlines += blocks[-1].count(b"\n")
    data = b"".join(reversed(blocks))
    if position > 0:
        data = data[data.index(b"\n") + 1:]  # the first line may be cut
    raws = data.split(b"\n")[:-1][-count:]
    if budget is not None:
        size, first = 0, len(raws)
        while first > 0 and (size + len(raws[first - 1]) <= budget or first == len(raws)):
            first -= 1
            size += len(raws[first])
        raws = raws[first:]
    lines = [parse(raw.decode("utf-8", "replace")) for raw in raws]
    return [line for line in lines if line is not None]


def life_event(line: LogLine) -> Event | None:
    """A launch.log line (read as a LogLine: kind as its stream) as the Event it was, if it
    tells a process's life, or is a line of the launch's own (a `log` of an action, such as
    LogInfo, or of the launcher: process None)."""
    if line.stream not in LIFE_KINDS:
        return None
    process, _, detail = line.text.partition(" ")
    if not process and line.stream != "log":  # a log line may be the launch's own
        return None
    fields: dict[str, str] = {}
    position = 0
    while (match := _DETAIL.match(detail, position)) is not None:
        fields[match.group(1)] = match.group(2)
        position = match.end()
    rest = detail[position:]
    reason = rest[len("reason="):] if rest.startswith("reason=") else None
    data: dict[str, object] = {"requested": fields.get("requested") == "1"}
    said = _SAID.match(rest) if line.stream == "log" and reason is None else None
    if said is not None:  # a LogInfo line, kept as ros2 launch prints it
        fields["level"], data["logger"], reason = said.groups()
    try:
        pid = int(fields["pid"]) if "pid" in fields else None
        code = int(fields["code"]) if "code" in fields else None
    except ValueError:
        return None
    if line.stream == "exited":  # launch.log keeps "requested" (asked or typed) only
        return ProcessExited(process=process or None, pid=pid, code=code, reason=reason,
                             level=fields.get("level") or "INFO", time=line.time, data=data,
                             cause=ExitCause.of(code or 0, bool(data["requested"])))
    return event_of(line.stream, process=process or None, pid=pid, code=code, reason=reason,
                    level=fields.get("level") or "INFO", time=line.time, data=data)


def log_size(path: Path) -> int:
    try:
        return os.path.getsize(path)
    except OSError:
        return 0


READ_LOG_LIMIT = 20_000
"""The most lines one `read_log` answer carries: a client pages on with `next`."""


def read_log(path: Path, start: int = 0, end: int | None = None, skip: int = 0,
             limit: int = READ_LOG_LIMIT, tail: bool = False) -> dict[str, object]:
    """The session protocol's `read_log`: the lines between bytes `start` and `end` (the
    file's size if None), after the first `skip` of them (lines a client already has).

    `tail`: the last `limit` lines of that range (a pane's scrollback), and `skipped`
    how many before them were left out; otherwise the first `limit`, and `next` is where
    to ask again. Lines are `[time, stream, text]`."""
    limit = max(0, min(int(limit), READ_LOG_LIMIT))
    size = log_size(path)
    end = size if end is None else min(int(end), size)
    start = max(0, int(start))
    if tail and skip <= 0 and start == 0:
        # backwards: a huge log costs only its tail
        lines = tail_lines(path, end, limit, MESSAGE_TEXT)
        return {"lines": [[line.time, line.stream, line.text] for line in lines],
                "next": end, "size": size, "skipped": None}
    kept: collections.deque[list[object]] = collections.deque()
    sizes: collections.deque[int] = collections.deque()
    seen = 0
    text = 0  # bytes of the lines kept: an answer carries at most MESSAGE_TEXT of them
    position = start
    try:
        handle = open(path, "rb")
    except OSError:
        return {"lines": [], "next": start, "size": size, "skipped": 0}
    with handle:
        handle.seek(start)
        while position < end:
            raw = handle.readline(end - position)
            if not raw.endswith(b"\n"):
                break  # a half-written last line is the next reader's
            if not tail and (len(kept) >= limit or (kept and text + len(raw) > MESSAGE_TEXT)):
                break  # the client asks again from `next`
            position += len(raw)
            if skip > 0:
                skip -= 1
                continue
            line = parse(raw.decode("utf-8", "replace"))
            if line is None:
                continue
            kept.append([line.time, line.stream, line.text])
            sizes.append(len(raw))
            text += len(raw)
            seen += 1
            while tail and (len(kept) > limit or (text > MESSAGE_TEXT and len(kept) > 1)):
                kept.popleft()  # the oldest go: `skipped` counts them
                text -= sizes.popleft()
    return {"lines": list(kept), "next": position, "size": size,
            "skipped": seen - len(kept)}
