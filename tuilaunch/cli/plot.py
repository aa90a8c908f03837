"""`tuilaunch plot [HOST:]NAME TOPIC FIELD [FIELD ...]`: a live plot of a topic's numeric
fields, full screen (`q` leaves), or with `--csv` one line per message for scripts and
spreadsheets (as `ros2 topic echo --csv`, with a header), until Ctrl+C or `--duration`.

The session server subscribes where the nodes run (engine/ros/plot/streams.py): the plot is sent
at most 20 points a second per field; `--csv` every message, as fast as the link carries.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from ..client.link import open_link
from ..engine.run.session.session_dir import SessionError
from .inspector import SLACK, streamed


def cmd_plot(options: argparse.Namespace) -> int:
    if options.duration is not None and not options.duration > 0:
        raise SessionError(f"--duration {options.duration:g} is not a positive number of "
                           "seconds")
    if options.csv:
        return _csv(options)
    return _screen(options)


def csv_cell(value: Any) -> str:
    """A value as the CSV prints it: exact (repr, the shortest that reads back the same),
    an integer field without a decimal point, nothing where a message had no value (an
    index past a sequence's end)."""
    if value is None:
        return ""
    return str(value) if isinstance(value, int) else repr(float(value))


def _csv(options: argparse.Namespace) -> int:
    link = open_link(options.name, timeout=SLACK)
    dropped = 0
    try:
        link.request("subscribe", max_lines=1, kinds=["plot"])  # no output lines wanted
        answer = link.request("plot", topic=options.topic, fields=options.fields, raw=True,
                              tag="csv")
        # the duration is the plot's, from its start: not the wait for the session's answer
        end = None if options.duration is None else time.monotonic() + options.duration
        out = sys.stdout
        out.write("time," + ",".join(answer["fields"]) + "\n")
        out.flush()
        first: float | None = None
        try:
            for data in streamed(link, "plot", end):
                dropped += int(data.get("dropped") or 0)
                lines = []
                for row in data.get("rows") or []:
                    if first is None:
                        first = float(row[0])
                    lines.append(f"{float(row[0]) - first:.6f},"
                                 + ",".join(csv_cell(v) for v in row[1:]) + "\n")
                out.write("".join(lines))
                out.flush()
        except KeyboardInterrupt:
            pass  # Ctrl+C ends the stream, as it ends ros2 topic echo: quietly, status 0
    finally:
        link.close()
    if dropped:
        print(f"tuilaunch plot: {dropped} message(s) of {options.topic} were left out: the "
              "link carried fewer lines than the topic sent", file=sys.stderr)
    return 0


def _screen(options: argparse.Namespace) -> int:
    if not (sys.stdout.isatty() and sys.stdin.isatty()):
        raise SessionError("the plot needs a terminal: --csv prints its values instead")
    from ..tui.plot_app import run_plot_app

    link = open_link(options.name, timeout=SLACK)
    try:
        link.request("subscribe", max_lines=1, kinds=["plot"])
        answer = link.request("plot", topic=options.topic, fields=options.fields, tag=1)
        return run_plot_app(link, answer, options.duration)
    finally:
        link.close()


__all__ = ["cmd_plot"]
