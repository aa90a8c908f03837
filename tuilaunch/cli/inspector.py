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
import sys
from collections.abc import Sequence
from typing import Any

from ..client.link import open_link
from ..engine.run.session.session_dir import SessionError

SLACK = 30.0
"""Seconds a reply may take beyond the work asked for (a bridge made for the request waits
for discovery; a topic's publisher is waited for 5 s; a node has 5 s to answer)."""


def ask(name: str, op: str, wait: float = 0.0, **fields: Any) -> Any:
    """One request's result; `wait`: the seconds the work itself takes."""
    link = open_link(name, timeout=wait + SLACK)
    try:
        return link.request(op, **fields)
    finally:
        link.close()


# --- topics ----------------------------------------------------------------------------------

def endpoint_text(endpoint: dict[str, Any]) -> str:
    process = endpoint.get("process")
    return f"{endpoint['node']} [{process}]" if process else endpoint["node"]


def cmd_topics(options: argparse.Namespace) -> int:
    fields = {"node": options.node} if options.node else {}
    graph = ask(options.name, "topics", **fields)
    if options.json:
        print(json.dumps(graph, indent=2))
        return 0
    topics = graph["topics"]
    if not topics:
        print("no topics" + (f" of {options.node}" if options.node else ""))
        return 0
    rows = [("TOPIC", "TYPE", "PUBLISHERS", "SUBSCRIBERS")]
    for topic in topics:
        rows.append((topic["name"], ", ".join(topic["types"]),
                     ", ".join(map(endpoint_text, topic["publishers"])) or "-",
                     ", ".join(map(endpoint_text, topic["subscribers"])) or "-"))
    table(rows)
    problems = [p for topic in topics for p in topic["qos_problems"]]
    if problems:
        print()
        print("QoS problems (these pairs exchange no message):")
        for problem in problems:
            print(f"  {problem}")
    return 0


def table(rows: Sequence[tuple[str, ...]]) -> None:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    for row in rows:
        print("  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip())


# --- hz --------------------------------------------------------------------------------------

def size_text(value: float) -> str:
    for unit in ("B", "KB", "MB"):
        if value < 1000:
            return f"{value:.2f} {unit}"
        value /= 1000
    return f"{value:.2f} GB"


def cmd_hz(options: argparse.Namespace) -> int:
    if not options.window > 0:
        raise SessionError(f"--window {options.window:g} is not a positive number of seconds")
    result = ask(options.name, "hz", options.window, topic=options.topic,
                 window=options.window)
    if options.json:
        print(json.dumps(result, indent=2))
    elif result["rate_hz"] is not None:
        print(f"average rate: {result['rate_hz']:.3f}")
        print(f"\twindow: {result['window_s']:g} s, {result['messages']} messages")
        print(f"average bandwidth: {size_text(result['bytes_per_s'] or 0.0)}/s")
    if result["rate_hz"] is None:
        print(f"tuilaunch hz: {result['topic']}: {result['messages']} message(s) in "
              f"{result['window_s']:g} s: too few for a rate", file=sys.stderr)
        return 1
    return 0


# --- echo ------------------------------------------------------------------------------------

def cmd_echo(options: argparse.Namespace) -> int:
    if options.count is not None and options.count < 1:
        raise SessionError(f"--count {options.count} is not a positive number")
    link = open_link(options.name, timeout=SLACK)
    try:
        link.request("subscribe", max_lines=1, kinds=["echo"])  # no output lines wanted
        fields: dict[str, Any] = {"topic": options.topic, "max_per_s": 0}
        if options.count is not None:
            fields["count"] = options.count
        link.request("echo", **fields)
        link.sock.settimeout(options.timeout)
        shown = 0
        try:
            for message in link.messages():
                if message.get("type") == "ended":
                    raise SessionError(f"session {link.name} ended")
                for event in message.get("events") or []:
                    data = event.get("data") or {}
                    if event.get("kind") != "echo":
                        continue
                    sys.stdout.write(data.get("text", ""))
                    sys.stdout.flush()
                    shown += 1
                    if options.count is not None and shown >= options.count:
                        return 0
        except TimeoutError:
            print(f"tuilaunch echo: {shown} message(s) of {options.topic} in "
                  f"{options.timeout:g} s", file=sys.stderr)
            return 1
        raise SessionError(f"session {link.name} closed the connection")
    finally:
        link.close()


# --- parameters and loggers ------------------------------------------------------------------

def cmd_params(options: argparse.Namespace) -> int:
    if options.dump:
        print(ask(options.name, "params_dump", node=options.node)["yaml"], end="")
        return 0
    try:
        with open(options.load, encoding="utf-8") as handle:
            text = handle.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise SessionError(f"parameter file {options.load} cannot be read: "
                           f"{getattr(exc, 'strerror', None) or exc}") from None
    results = ask(options.name, "params_load", node=options.node, yaml=text,
                  source=options.load)["results"]
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
        ask(name, "log_level", node=options.node, level=options.level)
    except SessionError as exc:
        if "has no logger service" in str(exc):
            link = open_link(name)
            try:
                process = link.request("find", short=True, process=options.node)
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
