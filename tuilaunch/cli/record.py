"""`tuilaunch record [HOST:]NAME [TOPIC ...] [-o FILE.mcap] [--duration S]`: the session's
topics (every topic its nodes publish when none is named) and its output lines, recorded
where the nodes run and written into an MCAP file on this computer, until Ctrl+C or the
duration; `--black-box` writes the session's black box now (in its log folder);
`--black-box-on SECONDS` switches it on for a running session.

`tuilaunch FILE --black-box SECONDS` reaches the session server it starts through its
environment (`black_box_option`): the server reads it before any process starts.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from typing import TYPE_CHECKING, Any

from ..client.link import Link, open_link
from ..engine.errors import LaunchError
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary import ros_requests as rq
from .inspect.inspector import SLACK

if TYPE_CHECKING:
    from ..client.inspect.recording import RecordFile


def black_box_option(seconds: float, size_mb: float) -> None:
    """`--black-box SECONDS --black-box-size MB`, checked, for the server started next."""
    from ..engine.ros.record.recorder import black_box_env

    if not seconds > 0:
        raise LaunchError(f"--black-box {seconds:g} is not a positive number of seconds")
    if not size_mb > 0:
        raise LaunchError(f"--black-box-size {size_mb:g} is not a positive number of MB")
    os.environ.update(black_box_env(seconds, int(size_mb * (1 << 20))))


def cmd_record(options: argparse.Namespace) -> int:
    if options.duration is not None and not options.duration > 0:
        raise SessionError(f"--duration {options.duration:g} is not a positive number of "
                           "seconds")
    if options.black_box or options.black_box_on is not None:
        return _black_box(options)
    from ..client.inspect.recording import RecordFile

    for topic in options.topic:
        if not topic.startswith("/"):
            raise SessionError(f"topic {topic!r} is not a full name: write /{topic}")
    link = open_link(options.name, timeout=SLACK)
    try:
        answer = link.request(rq.RecordStart(topics=options.topic))
        try:
            record = RecordFile(options.output, options.name)
        except OSError as exc:
            link.request(rq.RecordStop(recording=answer["recording"]))
            raise SessionError(str(exc)) from None
        _record(link, answer, record, options.duration)
    finally:
        link.close()
    return 0


def _record(link_: Link, answer: dict[str, Any], file: RecordFile,
            duration: float | None) -> None:
    ident = answer["recording"]
    named = answer.get("named") or []
    what = ", ".join(named) if named else \
        f"every topic of the launch's nodes ({len(answer.get('topics') or [])} so far)"
    print(f"recording {what} and the output into {file.path} (Ctrl+C ends)", file=sys.stderr)
    end = None if duration is None else time.monotonic() + duration
    try:
        try:
            while end is None or time.monotonic() < end:
                file.apply(link_.request(rq.RecordTake(recording=ident)))
        except KeyboardInterrupt:
            pass  # Ctrl+C ends the recording: what came is written, the file completed
        try:  # what the session took meanwhile, then the end of it there
            file.apply(link_.request(rq.RecordTake(recording=ident, wait=0)))
            link_.request(rq.RecordStop(recording=ident), short=True)
        except (SessionError, OSError, KeyboardInterrupt):
            pass  # the link is gone: the file holds what came, and is completed below
    finally:
        file.close()
    print(file.summary(), file=sys.stderr)


def _black_box(options: argparse.Namespace) -> int:
    link = open_link(options.name, timeout=SLACK)
    try:
        if options.black_box_on is not None:
            if options.black_box_on < 0 or not options.black_box_size > 0:
                raise SessionError("--black-box-on needs seconds >= 0 and a positive "
                                   "--black-box-size")
            status = link.request(rq.BlackBox(seconds=options.black_box_on,
                                           size=int(options.black_box_size * (1 << 20))))
            state = f"on: the last {status['seconds']:g} s" if status["on"] else "off"
            print(f"black box {state}")
            if not options.black_box:
                return 0
        written = link.request(rq.BlackBoxWrite())
    finally:
        link.close()
    where = f"{link.host}:" if link.host else ""
    print(f"{where}{written['path']} ({written['messages']} messages)")
    return 0


__all__ = ["black_box_option", "cmd_record"]
