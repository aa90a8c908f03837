"""`tuilaunch plot [HOST:]NAME TOPIC FIELD... [[HOST:]NAME] [TOPIC FIELD...]`: a live plot of
topics' numeric fields, of one session or several, full screen (`q` leaves), or with
`--csv` one line per message for scripts and spreadsheets (as `ros2 topic echo --csv`, with
a header), until Ctrl+C or `--duration`. `--stamp`: the messages' header.stamp is the time.

The session server subscribes where the nodes run (engine/ros/plot/streams.py): the plot is
sent at most 20 points a second per field; `--csv` every message, as fast as the link
carries. The plot reaches its sessions through their ports, as the TUI does
(tui/plot_app.py); `--csv` reads each session's blocking link on a thread of its own.
"""

from __future__ import annotations

import argparse
import queue
import sys
import threading
import time
from typing import Any

from ...client.inspect.plot_series import Source, column_name, new_tag
from ...client.inspect.plot_shapes import Asked, RowMerge, command_words
from ...client.link import Link, open_link, parse_session, resolve_name
from ...engine.errors import LaunchError
from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.requests import PlotStart, Subscribe
from .inspector import SLACK, streamed

CSV_FLUSH_S = 0.1
"""Seconds between the CSV's writes: a batch of every stream's rows, in time order."""


def cmd_plot(options: argparse.Namespace) -> int:
    if options.duration is not None and not options.duration > 0:
        raise SessionError(f"--duration {options.duration:g} is not a positive number of "
                           "seconds")
    asked = command_words(options.name, options.topic, options.fields)
    if options.csv:
        return _csv(options, asked)
    return _screen(options, asked)


# --- --csv -----------------------------------------------------------------------------------

def _csv(options: argparse.Namespace, asked: list[Asked]) -> int:
    stamp = bool(getattr(options, "stamp", False))
    links: dict[str, Link] = {}
    dropped = [0] * len(asked)
    try:
        for one in asked:
            if one.session not in links:
                link = links[one.session] = open_link(one.session, timeout=SLACK)
                link.request(Subscribe(max_lines=1, kinds=["plot"]))  # no output lines
        several = len(links) > 1
        header: list[str] = []
        widths: list[int] = []
        for index, one in enumerate(asked):
            answer = links[one.session].request(PlotStart(topic=one.topic, fields=one.fields,
                                                          raw=True, tag=index, stamp=stamp))
            header += [column_name(one.session, answer["topic"], f, several)
                       for f in answer["fields"]]
            widths.append(len(answer["fields"]))
        # the duration is the plot's, from its start: not the wait for the sessions' answers
        end = None if options.duration is None else time.monotonic() + options.duration
        out = sys.stdout
        out.write("time," + ",".join(header) + "\n")
        out.flush()
        # without --stamp the time counts from the first row; with it, epoch seconds
        merge = RowMerge(widths, relative=not stamp)
        rows: queue.Queue[Any] = queue.Queue()
        readers = [threading.Thread(target=_read, args=(link, end, rows), daemon=True)
                   for link in links.values()]
        for reader in readers:
            reader.start()
        running = len(readers)
        try:
            while running:
                try:
                    item = rows.get(timeout=CSV_FLUSH_S)
                except queue.Empty:
                    item = None
                if isinstance(item, BaseException):
                    raise item
                if item == "done":
                    running -= 1
                elif isinstance(item, tuple):
                    index, data = item
                    dropped[index] += int(data.get("dropped") or 0)
                    merge.add(index, data.get("rows") or [], time.monotonic())
                out.write("".join(merge.lines(time.monotonic())))
                out.flush()
        except KeyboardInterrupt:
            pass  # Ctrl+C ends the stream, as it ends ros2 topic echo: quietly, status 0
        out.write("".join(merge.lines(time.monotonic(), final=True)))
        out.flush()
    finally:
        for link in links.values():
            link.close()
    for one, count in zip(asked, dropped, strict=True):
        if count:
            print(f"tuilaunch plot: {count} message(s) of {one.topic} were left out: the "
                  "link carried fewer lines than the topic sent", file=sys.stderr)
    return 0


def _read(link: Link, end: float | None, out: queue.Queue[Any]) -> None:
    """One session's rows into `out` as (stream index, data), until `end`; then "done", or
    the error that ended it (a LinkLost, the session's end)."""
    try:
        for data in streamed(link, "plot", end):
            out.put((int(data.get("tag") or 0), data))
    except (LaunchError, OSError, ValueError) as exc:
        out.put(exc if isinstance(exc, LaunchError) else SessionError(str(exc)))
        return
    out.put("done")


# --- full screen -----------------------------------------------------------------------------

def _screen(options: argparse.Namespace, asked: list[Asked]) -> int:
    if not (sys.stdout.isatty() and sys.stdin.isatty()):
        raise SessionError("the plot needs a terminal: --csv prints its values instead")
    from ...client.remote_supervisor import RemoteSupervisor
    from ...client.served_session import ServedSession
    from ...engine.run.engine_thread import EngineThread
    from ...tui.inspect.plot_app import run_plot_app

    stamp = bool(getattr(options, "stamp", False))
    engine = EngineThread()
    ports: dict[str, Any] = {}
    runs: dict[str, Any] = {}
    try:
        for one in asked:
            if one.session in ports:
                continue
            where = parse_session(one.session)
            session = ServedSession(one.session, {})
            # a display of nothing but plots: one line a second at most of the output
            if where.host is None:
                opened = RemoteSupervisor.open(resolve_name(where.name), session, 0,
                                               max_lines=1, interval=1.0)
            else:
                opened = RemoteSupervisor.open_remote(where.host, where.name, session, 0,
                                                      max_lines=1, interval=1.0)
            port = ports[one.session] = engine.submit(opened).result(timeout=SLACK * 3)
            runs[one.session] = engine.submit(port.run(keep_alive=True))
        sources = []
        for one in asked:  # each stream asked here: a wrong field is one line, status 2
            source = Source(one.session, one.topic, one.fields, new_tag())
            answer = engine.submit(ports[one.session].request(
                PlotStart(topic=one.topic, fields=one.fields, tag=source.tag, stamp=stamp)))\
                .result(timeout=SLACK * 3)
            source.topic, source.fields = str(answer["topic"]), list(answer["fields"])
            source.type_name, source.stamped = str(answer["type"]), bool(answer["stamped"])
            sources.append(source)
        run_plot_app(engine, ports, sources, stamp, options.duration, runs)
    finally:
        for port in ports.values():
            try:
                engine.submit(port.detach()).result(timeout=5)
            except Exception:  # gone already: nothing to leave
                pass
        engine.stop()
    return 0


__all__ = ["cmd_plot"]
