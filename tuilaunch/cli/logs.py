"""`tuilaunch logs [HOST:]NAME [PROCESS] [-f] [--since T] [--level L]`: a session's output.

Read from the log files (on another machine, page by page through the server's
`read_log`), merged in time order; with `-f`, the lines that come after, from the events.
"""

from __future__ import annotations

import argparse
import datetime
import heapq
import os
import re
import sys
import time
from collections.abc import Iterator
from pathlib import Path

from ..client.link import Link, open_link
from ..engine.run.process.output import strip_ansi
from ..engine.run.session.log_reader import LogLine, read_lines
from ..engine.run.session.protocol import event_from_dict
from ..engine.run.session.session_dir import SessionError
from ..tui.output_store import LEVELS, level_of


def cmd_logs(options: argparse.Namespace) -> int:
    since = parse_since(options.since) if options.since else None
    minimum = LEVELS.index(options.level) if options.level else 0
    link = open_link(options.name, timeout=None)
    try:
        status = link.request("status", short=True, resources=False)
        log_dir = Path(status["log_dir"])
        wanted = [p["id"] for p in status["processes"] if p["state"] != "skipped"]
        if options.process:
            wanted = [link.request("find", short=True, process=options.process)]
        prefixed = len(wanted) > 1 or not options.process
        offsets: dict[str, int | None] = dict.fromkeys(wanted)
        if options.follow:
            subscribed = link.request("subscribe", short=True)
            offsets = {p: subscribed["offsets"].get(p, 0) for p in wanted}
        out = sys.stdout
        colour = out.isatty() and not os.environ.get("NO_COLOR")

        def show(process: str, line: LogLine) -> None:
            if since is not None and line.time < since:
                return
            text = line.text if colour else strip_ansi(line.text)
            if minimum and level_of(text, line.stream) < minimum:
                return
            out.write(f"[{process}] {text}\n" if prefixed else text + "\n")

        if link.host is None:
            streams = [tagged(p, read_lines(log_dir / f"{p}.log", offsets[p]))
                       for p in wanted]
        else:  # the files are on the other machine: its server reads them for us
            streams = [tagged(p, remote_lines(link, p, offsets[p])) for p in wanted]
        for _, process, line in heapq.merge(*streams, key=lambda item: item[0]):
            show(process, line)
        out.flush()
        if not options.follow:
            return 0
        for message in link.messages():
            if message.get("type") != "events":
                continue
            for data in message.get("events") or []:
                event = event_from_dict(data)
                if event.kind == "output" and event.process in offsets:
                    for text in event.lines:
                        show(event.process, LogLine(event.time, event.stream or "stdout",
                                                    text))
                elif event.kind == "dropped" and event.process in offsets:
                    print(f"tuilaunch logs: {event.code} lines of {event.process} skipped "
                          f"(too slow a reader); they are in {log_dir}", file=sys.stderr)
            out.flush()
        return 0
    finally:
        link.close()


def remote_lines(link: Link, process: str, end: int | None) -> Iterator[LogLine]:
    """A log file on the session's machine, page by page through `read_log`."""
    start = 0
    if end is None:
        end = int(link.request("read_log", short=True, process=process, limit=0)["size"])
    while start < end:
        page = link.request("read_log", short=True, process=process, start=start, end=end)
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
