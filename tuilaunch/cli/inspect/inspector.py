"""`tuilaunch topics | hz | echo | params | log-level`: the inspector's session commands.

Each asks the session server, which runs where the nodes run and knows which process is
which node (engine/ros/inspector.py); the answers are printed as `ros2 topic` and
`ros2 param` print theirs. Every wait has a deadline: a node that does not answer, a topic
nobody publishes, a server that is stuck, each ends the command with one line and a
non-zero status.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import textwrap
import time
from collections.abc import Iterator
from typing import Any, TypeVar

from ...client.link import Link, open_link
from ...engine.run.session.protocol import ProtocolError
from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.request import Request
from ...engine.run.vocabulary.requests import (
    EchoStart,
    Find,
    HzRead,
    HzWatch,
    LogLevel,
    ParamsDump,
    ParamsLoad,
    Subscribe,
    Topics,
)

R = TypeVar("R")

SLACK = 30.0
"""Seconds a reply may take beyond the work asked for (a bridge made for the request waits
for discovery; a topic's publisher is waited for 5 s; a node has 5 s to answer)."""


def ask(name: str, request: Request[R], wait: float = 0.0) -> R:
    """One request's result; `wait`: the seconds the work itself takes."""
    link = open_link(name, timeout=wait + SLACK)
    try:
        return link.request(request)
    finally:
        link.close()


# --- topics ----------------------------------------------------------------------------------

def cmd_topics(options: argparse.Namespace) -> int:
    graph = ask(options.name, Topics(node=options.node or None))
    if options.json:
        print(json.dumps(graph, indent=2))
        return 0
    topics = graph["topics"]
    if not topics:
        print("no topics" + (f" of {options.node}" if options.node else ""))
        return 0
    width = shutil.get_terminal_size().columns  # COLUMNS first, then the terminal, else 80
    if options.verbose:
        print("\n".join(topic_info(topic) for topic in topics).rstrip("\n"))
        return 0
    print("\n".join(topic_lines(topics, width)))
    problems = [p for topic in topics for p in topic["qos_problems"]]
    if problems:
        print()
        print("QoS problems (these pairs exchange no message):")
        for problem in problems:
            print(textwrap.fill(problem, width, initial_indent="  ", subsequent_indent="    "))
    return 0


def cut(text: str, width: int) -> str:
    return text if len(text) <= width else text[:max(width - 1, 0)] + "…"


def topic_lines(topics: list[dict[str, Any]], width: int) -> list[str]:
    """One line per topic within `width`: name, type, publisher and subscriber counts, and
    `!!` where a pair cannot talk. The type is cut first, then the name."""
    rows = [(t["name"], ", ".join(t["types"]), str(len(t["publishers"])),
             str(len(t["subscribers"])), "!!" if t["qos_problems"] else "") for t in topics]
    header = ("TOPIC", "TYPE", "PUB", "SUB", "QOS")
    pubs = max(len(header[2]), *(len(r[2]) for r in rows))
    subs = max(len(header[3]), *(len(r[3]) for r in rows))
    fixed = pubs + subs + len(header[4]) + 8  # four gaps of two
    names = max(len(header[0]), *(len(r[0]) for r in rows))
    types = max(len(header[1]), *(len(r[1]) for r in rows))
    room = max(width - fixed, 16)
    if names + types > room:  # the type gives way first, down to 12, then the name
        types = max(room - names, min(types, 12))
        names = max(room - types, 4)
    lines = []
    for row in (header, *rows):
        line = (f"{cut(row[0], names).ljust(names)}  {cut(row[1], types).ljust(types)}  "
                f"{row[2].rjust(pubs)}  {row[3].rjust(subs)}  {row[4]}")
        lines.append(line.rstrip())
    return lines


def topic_info(topic: dict[str, Any]) -> str:
    """`ros2 topic info -v`'s shape, each endpoint with its node, process and QoS."""
    lines = [f"Topic: {topic['name']}", f"Type: {', '.join(topic['types'])}", ""]
    for kind, label in (("publishers", "Publisher"), ("subscribers", "Subscription")):
        lines += [f"{label} count: {len(topic[kind])}", ""]
        for endpoint in topic[kind]:
            qos = endpoint.get("qos") or {}
            node = endpoint["node"]
            namespace, _, name = node.rpartition("/")
            history = str(qos.get("history", "unknown")).upper()
            depth = qos.get("depth")
            lines += [f"Node name: {name}", f"Node namespace: {namespace or '/'}",
                      f"Process: {endpoint.get('process') or '(not of this launch)'}",
                      f"Topic type: {', '.join(topic['types'])}",
                      f"Endpoint type: {label.upper()}", "QoS profile:",
                      f"  Reliability: {str(qos.get('reliability')).upper()}",
                      f"  History (Depth): {history}" + (f" ({depth})" if depth else ""),
                      f"  Durability: {str(qos.get('durability')).upper()}",
                      f"  Deadline: {str(qos.get('deadline')).capitalize()}",
                      f"  Liveliness: {str(qos.get('liveliness')).upper()}",
                      "  Liveliness lease duration: "
                      f"{str(qos.get('liveliness_lease_duration')).capitalize()}", ""]
    for problem in topic["qos_problems"]:
        lines.append(f"QoS problem: {problem}")
    if topic["qos_problems"]:
        lines.append("")
    return "\n".join(lines) + "\n"


# --- hz --------------------------------------------------------------------------------------

def size_text(value: float) -> str:
    for unit in ("B", "KB", "MB"):
        if value < 1000:
            return f"{value:.2f} {unit}"
        value /= 1000
    return f"{value:.2f} GB"


def hz_block(result: dict[str, Any]) -> str:
    """ros2 topic hz's two lines, then ros2 topic bw's two (its units: one for all four
    figures, chosen by the bandwidth)."""
    lines = [f"average rate: {result['rate_hz']:.3f}",
             f"\tmin: {result['min_s']:.3f}s max: {result['max_s']:.3f}s std dev: "
             f"{result['std_dev_s']:.5f}s window: {result['window']}"]
    bandwidth = result.get("bytes_per_s")
    if bandwidth is not None:
        scale, unit = next(((s, u) for s, u in ((1, "B"), (1e3, "KB"), (1e6, "MB"))
                            if bandwidth < s * 1000), (1e6, "MB"))
        figures = [f"{result[k] / scale:.2f} {unit}" for k in ("size_mean", "size_min",
                                                                "size_max")]
        lines += [f"average bandwidth: {bandwidth / scale:.2f} {unit}/s from "
                  f"{result['window'] + 1} messages",
                  f"\tmessage size mean: {figures[0]} min: {figures[1]} max: {figures[2]}"]
    return "\n".join(lines) + "\n"


def streamed(link: Link, kind: str, end: float | None) -> Iterator[dict[str, Any]]:
    """The data of the session's `kind` events (hz, echo) as they come, until `end` (a
    monotonic time; None: until Ctrl+C); the session's end is an error."""
    link.timeout = None
    while True:
        try:
            message = link.receive_until(end)
        except TimeoutError:
            return
        if message is None:
            lost = link.lost()
            if lost is not None:  # the ssh link, not the session: exit 1, not 2
                raise lost
        if message is None or message.get("type") == "ended":
            raise SessionError(f"session {link.label} ended")  # as typed: HOST:NAME
        for event in message.get("events") or []:
            if event.get("kind") == kind:
                yield event.get("data") or {}


def _figures_now(link: Link, topic: str) -> dict[str, Any] | None:
    """The session's hz figures at this moment; None when it cannot say at once (Ctrl+C
    leaves without them rather than wait)."""
    try:
        figures: dict[str, Any] = link.request(HzRead(topic=topic), short=True)
    except (SessionError, ProtocolError, OSError, ValueError):
        return None
    return figures


def cmd_hz(options: argparse.Namespace) -> int:
    """A block every second until Ctrl+C (then the figures so far), or once after
    `--duration` (`--json`: one object, after 5 s unless told)."""
    if options.window < 1:
        raise SessionError(f"--window {options.window} is not a positive number of messages")
    duration = options.duration if options.duration is not None else \
        (5.0 if options.json else None)
    if duration is not None and not duration > 0:
        raise SessionError(f"--duration {duration:g} is not a positive number of seconds")
    link = open_link(options.name, timeout=SLACK)
    try:
        link.request(Subscribe(max_lines=1, kinds=["hz"]))  # no output lines wanted
        link.request(HzWatch(topic=options.topic, messages=options.window))
        end = None if duration is None else time.monotonic() + duration
        shown = 0  # messages counted at the last block: a block only when new ones came
        last: dict[str, Any] | None = None
        try:
            for last in streamed(link, "hz", end):
                if end is None and last["rate_hz"] is not None and last["messages"] > shown:
                    shown = last["messages"]
                    sys.stdout.write(hz_block(last))
                    sys.stdout.flush()
        except KeyboardInterrupt:
            # Ctrl+C ends a stream: the figures as they stand now, as the last word, unless
            # the block on screen already says them (a block repeated adds nothing)
            now = _figures_now(link, options.topic)
            if now is not None and now["rate_hz"] is not None and now["messages"] > shown:
                sys.stdout.write(hz_block(now))
            return 0
        result = link.request(HzRead(topic=options.topic), short=True)
    finally:
        link.close()
    if options.json:
        print(json.dumps(result, indent=2))
    elif result["rate_hz"] is not None:
        sys.stdout.write(hz_block(result))
    if result["rate_hz"] is None:
        print(f"tuilaunch hz: {result['topic']}: {result['messages']} message(s) in "
              f"{result['elapsed_s']:g} s: too few for a rate", file=sys.stderr)
        return 1
    return 0


# --- echo ------------------------------------------------------------------------------------

def cmd_echo(options: argparse.Namespace) -> int:
    """Messages until Ctrl+C, `--count N` or `--once`; `--timeout S` is the whole wait,
    the publisher's included."""
    count = 1 if options.once else options.count
    if count is not None and count < 1:
        raise SessionError(f"--count {count} is not a positive number")
    if options.timeout is not None and not options.timeout > 0:
        raise SessionError(f"--timeout {options.timeout:g} is not a positive number of "
                           "seconds")
    end = None if options.timeout is None else time.monotonic() + options.timeout
    link = open_link(options.name, timeout=SLACK)
    shown = 0
    try:
        link.request(Subscribe(max_lines=1, kinds=["echo"]))  # no output lines wanted
        # every message (max_per_s 0); --timeout is also how long a publisher is waited for
        link.request(EchoStart(options.topic, count, 0, options.timeout))
        for data in streamed(link, "echo", end):
            sys.stdout.write(data.get("text", ""))
            sys.stdout.flush()
            shown += 1
            if count is not None and shown >= count:
                return 0
    finally:
        link.close()
    # the time ran out: enough when no count was asked and something came
    if count is None and shown:
        return 0
    wanted = f" of {count}" if count is not None else ""
    print(f"tuilaunch echo: {shown}{wanted} message(s) of {options.topic} in "
          f"{options.timeout:g} s", file=sys.stderr)
    return 1


# --- parameters and loggers ------------------------------------------------------------------

def cmd_params(options: argparse.Namespace) -> int:
    if options.dump:
        print(ask(options.name, ParamsDump(node=options.node))["yaml"], end="")
        return 0
    try:
        with open(options.load, encoding="utf-8") as handle:
            text = handle.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise SessionError(f"parameter file {options.load} cannot be read: "
                           f"{getattr(exc, 'strerror', None) or exc}") from None
    results = ask(options.name,
                  ParamsLoad(node=options.node, yaml=text, source=options.load))["results"]
    for result in results:
        if result["ok"]:
            reason = f" ({result['reason']})" if result["reason"] else ""
            print(f"{result['name']}: set{reason}")
        else:
            print(f"{result['name']}: refused: {result['reason'] or 'no reason given'}")
    if not results:
        print(f"{options.load} gives {options.node} no parameter")
    return 0 if all(r["ok"] for r in results) else 1


def cmd_log_level(options: argparse.Namespace) -> int:
    name = options.name
    try:
        ask(name, LogLevel(node=options.node, level=options.level))
    except SessionError as exc:
        if "has no logger service" in str(exc):
            link = open_link(name)
            try:
                process = link.request(Find(process=options.node), short=True)
            except SessionError:
                raise exc from None
            finally:
                link.close()
            raise SessionError(f"{exc.message} (tuilaunch restart {name} {process} "
                               f"--log-level {options.level.upper()})") from None
        raise
    print(f"{options.node}: logger level {options.level.upper()}")
    return 0


__all__ = ["cmd_echo", "cmd_hz", "cmd_log_level", "cmd_params", "cmd_topics"]
