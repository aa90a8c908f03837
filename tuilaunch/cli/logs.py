"""`tuilaunch logs [HOST:]NAME [PROCESS] [-f] [-n N] [--since T] [--level L]`: a session's
output, and its processes' lives (starts, exits with their code or signal, respawns) in the
words `--headless` prints them, so `--level ERROR` shows a crash; without a PROCESS, the
launch's own lines too (LogInfo's), as `--headless` prints them among the others.

Read from the log files and launch.log (on another machine, through the server's
`read_log`), merged in time order; with `-f`, the lines that come after, from the events.
"""

from __future__ import annotations

import argparse
import collections
import datetime
import heapq
import io
import os
import re
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Protocol

from ..client.link import Link, open_link
from ..engine.run.events import Dropped, Event, Log, Output
from ..engine.run.session.log_reader import (
    LAUNCH_LOG,
    LIFE_KINDS,
    LogLine,
    life_event,
    log_size,
    read_lines,
    tail_lines,
)
from ..engine.run.session.protocol import event_from_dict
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary.requests import Find, ReadLog, Status, Subscribe
from ..engine.run.vocabulary.text import strip_ansi
from ..tui.output_store import LEVELS, level_of
from .headless import Printer


class Lines(Protocol):
    """Where the lines go: stdout, or one shared by several sessions' threads."""

    def write(self, text: str, /) -> int: ...

    def flush(self) -> None: ...


def cmd_logs(options: argparse.Namespace) -> int:
    show_logs(options, options.name)
    return 0


def show_logs(options: argparse.Namespace, address: str | None, out: Lines | None = None,
              tag: str = "") -> str | None:
    """The logs of the session at `address` as `options` ask, written to `out` (stdout),
    each line after `tag` (`logs -f` of several sessions: `HOST:NAME `). Following, it
    returns once the session closes the connection: None when it ended, else why not
    (a link lost)."""
    since = parse_since(options.since) if options.since else None
    minimum = LEVELS.index(options.level) if options.level else 0
    last = options.lines
    if last is not None and last < 0:
        raise SessionError(f"--lines {last} is not a number of lines", hint="0 or more")
    link = open_link(address, timeout=None)
    try:
        status = link.request(Status(resources=False), short=True)
        log_dir = Path(status.log_dir)
        wanted = [p.id for p in status.processes if p.state != "skipped"]
        processes = {p.id for p in status.processes}
        if options.process:
            wanted = [link.request(Find(process=options.process), short=True)]
        prefixed = len(wanted) > 1 or not options.process
        offsets: dict[str, int | None] = dict.fromkeys(wanted)
        if options.follow:
            subscribed = link.request(Subscribe(), short=True)
            offsets = {p: subscribed["offsets"].get(p, 0) for p in wanted}
        # launch.log's size after the subscription: its events come after, as events
        launch_end = _launch_log_size(link, log_dir)
        out = out or sys.stdout
        colour = sys.stdout.isatty() and not os.environ.get("NO_COLOR")
        life = Printer(io.StringIO())
        told: set[tuple[str, str, int | None, int, str | None]] = set()
        kept: collections.deque[str] | None = None if last is None else \
            collections.deque(maxlen=last)

        def show(process: str, line: LogLine) -> None:
            if since is not None and line.time < since:
                return
            text = line.text if colour else strip_ansi(line.text)
            if minimum and level_of(text, line.stream) < minimum:
                return
            # a life line names its process already, as --headless prints it
            text = f"{tag}[{process}] {text}\n" if prefixed and line.stream != "life" \
                else f"{tag}{text}\n"
            if kept is not None:
                kept.append(text)
            else:
                out.write(text)

        def tell(event: Event) -> None:
            """A start, an exit, a respawn ... in the headless printer's words."""
            # its words too: an action may say two things within a millisecond
            key = (event.kind, event.process or "", event.pid, round(event.time * 1000),
                   event.reason)
            if key in told:
                return  # launch.log had it, and the subscription's history too
            told.add(key)
            text = life.format(event).replace(", cmd ''", "").rstrip("\n")
            if text:
                show(event.process or "launch", LogLine(event.time, "life", text))

        def ours(event: Event) -> bool:
            """A process's life, or (with no PROCESS asked for) the launch's own line, such
            as a LogInfo's, as --headless prints it among the processes' lines."""
            if event.process in offsets:
                return True
            return not options.process and isinstance(event, Log) and \
                event.process not in processes

        # without a filter, -n N reads only each file's tail
        tail = last if last is not None and since is None and not minimum else None
        if link.host is None:
            streams = [tagged(p, _local_lines(log_dir / f"{p}.log", offsets[p], tail))
                       for p in wanted]
            events = read_lines(log_dir / "launch.log", launch_end)
        else:  # the files are on the other machine: its server reads them for us
            streams = [tagged(p, _remote_tail(link, p, offsets[p], tail) if tail is not None
                              else remote_lines(link, p, offsets[p])) for p in wanted]
            events = remote_lines(link, LAUNCH_LOG, launch_end)
        lives = [(e.time, e.process or "", e) for e in map(life_event, events)
                 if e is not None and ours(e)]
        for _, process, item in heapq.merge(*streams, lives, key=lambda item: item[0]):
            if isinstance(item, Event):
                tell(item)
            elif isinstance(item, LogLine):
                show(process, item)
        if kept is not None:
            out.write("".join(kept))
            kept = None  # followed lines are printed as they come
        out.flush()
        if not options.follow:
            return None
        ended = False
        for message in link.messages():
            ended = ended or message.get("type") == "ended"
            if message.get("type") != "events":
                continue
            for data in message.get("events") or []:
                event = event_from_dict(data)
                if isinstance(event, Output) and event.process in offsets:
                    for text in event.lines:
                        show(event.process, LogLine(event.time, event.stream or "stdout",
                                                    text))
                elif isinstance(event, Dropped) and event.process in offsets:
                    print(f"tuilaunch logs: {tag}{event.code} lines of {event.process} skipped "
                          f"(too slow a reader); they are in {log_dir}", file=sys.stderr)
                elif event.kind in LIFE_KINDS and ours(event):
                    tell(event)
            out.flush()
        if ended:
            return None
        lost = link.lost()
        return "the connection closed" if lost is None else lost.message
    finally:
        link.close()


def _launch_log_size(link: Link, log_dir: Path) -> int:
    if link.host is None:
        return log_size(log_dir / "launch.log")
    return int(link.request(ReadLog(process=LAUNCH_LOG, limit=0), short=True)["size"])


def _local_lines(path: Path, end: int | None, tail: int | None) -> Iterator[LogLine]:
    if tail is None:
        return read_lines(path, end)
    return iter(tail_lines(path, log_size(path) if end is None else end, tail))


def _remote_tail(link: Link, process: str, end: int | None, count: int) -> Iterator[LogLine]:
    """The last `count` lines of a log file on the session's machine, in one answer."""
    if count <= 0:
        return
    page = link.request(ReadLog(process=process, end=end, limit=count, tail=True), short=True)
    for stamp, stream, text in page["lines"]:
        yield LogLine(float(stamp), str(stream), str(text))


def remote_lines(link: Link, process: str, end: int | None) -> Iterator[LogLine]:
    """A log file on the session's machine, page by page through `read_log`."""
    start = 0
    if end is None:
        end = int(link.request(ReadLog(process=process, limit=0), short=True)["size"])
    while start < end:
        page = link.request(ReadLog(process=process, start=start, end=end), short=True)
        for stamp, stream, text in page["lines"]:
            yield LogLine(float(stamp), str(stream), str(text))
        if int(page["next"]) <= start:
            return  # a half-written last line: the events carry it
        start = int(page["next"])


def tagged(process: str, lines: Iterator[LogLine]) -> Iterator[tuple[float, str, LogLine]]:
    for line in lines:
        yield line.time, process, line


_DURATION = re.compile(r"^(\d+(?:\.\d+)?)\s*(s|m|h|d)$")


def parse_since(text: str) -> float:
    match = _DURATION.match(text.strip())
    if match:
        unit = {"s": 1, "m": 60, "h": 3600, "d": 86400}[match.group(2)]
        return time.time() - float(match.group(1)) * unit
    try:
        return float(text)
    except ValueError:
        pass
    try:
        moment = datetime.datetime.fromisoformat(text)
    except ValueError:
        try:
            clock = datetime.time.fromisoformat(text)
        except ValueError:
            raise SessionError(f"--since {text!r} is not a time",
                               hint="30s, 5m, 2h, a unix time, 2026-11-22T08:30:00 or 08:30")\
                from None
        moment = datetime.datetime.combine(datetime.date.today(), clock)
    return moment.timestamp()
