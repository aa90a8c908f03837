"""The recordings and the black box of one launch, where its nodes run: a supervisor plugin
(run/plugins.py) answering `record_start`, `record_take`, `record_stop` (a client's
recording, pulled by it: `tuilaunch record`, the Topics tab), `black_box` (switched on, off,
or asked how it is) and `black_box_write` (written now: `b`, `tuilaunch record --black-box`).

Every recorded topic is subscribed once (taker.py), whatever the number of recordings; its
messages go to the black box's tape and to each recording's tape that wants the topic. A
recording's tape holds what its client has not pulled yet, bounded in bytes: a client whose
link is slower than the topics loses the oldest, counted and said. The launch's output lines
and its process events go to every tape as `rcl_interfaces/msg/Log` on `/tuilaunch/output`.

The black box (`--black-box SECONDS`, `--black-box-size`) keeps the last SECONDS of every
topic the launch's nodes publish and of every line; when a process dies unasked (a crash, a
non-zero exit, a signal nobody sent) it is written AFTER_DEATH later into the session's log
folder, at most once a minute per process, and the path is said as a line of the process
(the pane, launch.log, `tuilaunch logs`).

This module imports neither rclpy nor mcap: a launch without a recording or a black box
loads neither; the taker and the writer come with the first use.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ...errors import LaunchError
from ...run.events import Event, Log, Output, ProcessExited, Started
from ...run.plugins import Handlers, Plugin
from ...run.vocabulary.ros_requests import (
    BlackBox,
    BlackBoxWrite,
    RecordStart,
    RecordStop,
    RecordTake,
)
from ..graph.stream_hooks import in_background, stopped

if TYPE_CHECKING:
    from ...run.supervisor.supervisor import Supervisor
    from ..inspector import Inspector
    from .tape import Channel, Tape

BLACK_BOX_ENV = "TUILAUNCH_BLACK_BOX"
"""`SECONDS:BYTES`, set by the command line for the session server it starts (taken out of
the environment here, so the launch's processes do not inherit it)."""
DEFAULT_SIZE = 256 << 20
AFTER_DEATH = 3.0
"""Seconds recorded after a death before the black box is written: the other nodes'
reaction, the last lines still in the pipes."""
ONE_FILE_PER = 60.0
"""A process in a crash loop writes a black box at most once in this many seconds."""
PENDING = 256 << 20
"""Bytes a recording keeps for its client before dropping the oldest."""
TAKE_BYTES = 8 << 20
"""At most this much of a recording in one `record_take` reply (base64 in one JSON line)."""
TAKE_WAIT = 0.5
FOLLOW_PERIOD = 1.0
"""Seconds between looks at the graph for topics to record that appeared."""
NOT_RECORDED = frozenset({"/rosout", "/parameter_events"})
"""Topics every node publishes, left out of "all the launch's topics": /rosout repeats the
output lines, which are recorded on /tuilaunch/output. Named, they are recorded."""


def black_box_config() -> tuple[float, int] | None:
    value = os.environ.pop(BLACK_BOX_ENV, "")
    if not value:
        return None
    seconds, _, size = value.partition(":")
    return float(seconds), int(size or DEFAULT_SIZE)


def black_box_env(seconds: float, size: int) -> dict[str, str]:
    """What the command line sets for the server it starts (`--black-box`)."""
    return {BLACK_BOX_ENV: f"{seconds:g}:{size}"}


@dataclass
class Recording:
    id: int
    client: int | None
    topics: set[str] | None  # None: all the launch's topics
    tape: Tape
    told: set[str] = field(default_factory=set)  # channels its client was sent
    started: float = field(default_factory=time.time)


class Recorder(Plugin):
    def __init__(self, supervisor: Supervisor, inspector: Inspector) -> None:
        self.supervisor = supervisor
        self.inspector = inspector
        self.box: Tape | None = None
        self.box_seconds = 0.0
        self.recordings: dict[int, Recording] = {}
        self.next_id = 0
        self.taker: Any = None  # Taker, made with the first topic
        self.channels: dict[str, Channel] = {}
        self.unrecorded: dict[str, str] = {}  # topic -> why it cannot be recorded
        self.follow_task: asyncio.Task[None] | None = None
        self.written: dict[str, tuple[float, str]] = {}  # process -> (monotonic, path)
        self.files: list[str] = []
        self.pending: set[asyncio.Task[Any]] = set()
        config = black_box_config()
        if config is not None:
            self._box_on(*config)
        supervisor.subscribe(self.on_event)

    # --- the plugin's hooks ------------------------------------------------------------------

    def run_started(self) -> None:
        if self.box is not None:
            self._follow()

    def handlers(self, find_process: Callable[[str], str]) -> Handlers:
        return {RecordStart: self.record_start, RecordTake: self.record_take,
                RecordStop: self.record_stop, BlackBox: self.black_box,
                BlackBoxWrite: self.black_box_write}

    def client_gone(self, client: int) -> None:
        for recording in [r for r in self.recordings.values() if r.client == client]:
            del self.recordings[recording.id]

    def snapshot(self) -> dict[str, Any]:
        return {"black_box": self.status()} if self.box is not None else {}

    async def close(self) -> None:
        await stopped(self.follow_task)
        for task in list(self.pending):  # a black box being written is finished
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        taker, self.taker = self.taker, None
        if taker is not None:
            await asyncio.to_thread(taker.close)

    # --- what goes on every tape -------------------------------------------------------------

    def _tapes(self, topic: str) -> list[Tape]:
        tapes = [r.tape for r in self.recordings.values()
                 if r.topics is None or topic in r.topics]
        if self.box is not None:
            tapes.append(self.box)
        return tapes

    def sink(self, topic: str, time_ns: int, data: bytes) -> None:
        """A message taken (the taker's thread)."""
        for tape in self._tapes(topic):
            tape.add(topic, time_ns, data)

    def on_event(self, event: Event) -> None:
        """Output lines and process events onto the tapes (the server's loop)."""
        if self.box is None and not self.recordings:
            return
        from .tape import LAUNCH, OUTPUT_TOPIC, line_message, log_message

        time_ns = int(event.time * 1e9)
        tapes = [r.tape for r in self.recordings.values()]
        if self.box is not None:
            tapes.append(self.box)
        if isinstance(event, Output) and event.process is not None:
            messages = [line_message(time_ns, event.process, line, event.stream)
                        for line in event.lines]
        elif isinstance(event, Started) and event.process is not None and event.pid:
            messages = [log_message(time_ns, 20, LAUNCH,
                                    f"{event.process}: process started with pid {event.pid}")]
        elif isinstance(event, ProcessExited) and event.process is not None:
            level = 40 if event.crashed else 20
            messages = [log_message(time_ns, level, LAUNCH,
                                    f"{event.process}: process has "
                                    f"{'died' if event.crashed else 'finished'}: "
                                    f"{event.reason or f'exit code {event.code}'}")]
            if event.crashed and self.box is not None:
                self._spawn(self._write_after_death(event.process))
        else:
            return
        for tape in tapes:
            for message in messages:
                tape.add(OUTPUT_TOPIC, time_ns, message)

    def _spawn(self, coroutine: Any) -> None:
        in_background(self.pending, coroutine)

    # --- the topics recorded -----------------------------------------------------------------

    def _follow(self) -> None:
        if self.follow_task is None or self.follow_task.done():
            self.follow_task = asyncio.ensure_future(self._follow_graph())

    def _wanted(self) -> tuple[bool, set[str]]:
        """(whether all the launch's topics are wanted, the topics named)."""
        every = self.box is not None or any(r.topics is None for r in self.recordings.values())
        named = set().union(*(r.topics for r in self.recordings.values()
                              if r.topics is not None))
        return every, named

    async def _follow_graph(self) -> None:
        while self.box is not None or self.recordings:
            try:
                await self.subscribe_new()
            except LaunchError as exc:  # ROS is not available here: said once a recording asks
                self.unrecorded[""] = str(exc)
            await asyncio.sleep(FOLLOW_PERIOD)

    async def subscribe_new(self) -> None:
        every, named = self._wanted()
        bridge = await self.inspector.bridge()
        node = bridge.node
        names = await asyncio.to_thread(node.get_topic_names_and_types)
        launch_nodes = set(self.inspector.node_processes()) if every else set()
        for topic, _types in names:
            if topic in self.channels or (topic not in named and
                                          (not every or topic in NOT_RECORDED)):
                continue
            infos = await asyncio.to_thread(node.get_publishers_info_by_topic, topic)
            if not infos:
                continue
            if topic not in named and not any(_full_name(i) in launch_nodes for i in infos):
                continue
            await self._subscribe(node, topic, infos)

    async def _subscribe(self, node: Any, topic: str, infos: list[Any]) -> None:
        from ..graph.rates import matching_qos, message_class
        from ..messages import MessageError
        from .definitions import full_definition
        from .mcap_out import qos_yaml
        from .tape import Channel

        type_name = infos[0].topic_type
        try:
            cls = message_class(type_name)
        except MessageError as exc:
            self.unrecorded[topic] = str(exc)
            return
        profiles = [i.qos_profile for i in infos]
        channel = Channel(topic, type_name, await asyncio.to_thread(full_definition, type_name),
                          qos_yaml(profiles))
        self.channels[topic] = channel
        self.unrecorded.pop(topic, None)
        if self.taker is None:
            from .taker import Taker

            self.taker = Taker(node, self.sink)
        self.taker.add(topic, cls, matching_qos(profiles))

    # --- recordings ----------------------------------------------------------------------------

    async def record_start(self, request: RecordStart, client: int) -> dict[str, Any]:
        from .tape import Tape

        topics = request.topics
        if not all(isinstance(t, str) and t.startswith("/") for t in topics):
            raise ValueError("record needs topics as a list of names starting with /")
        self.next_id += 1
        recording = Recording(self.next_id, client,
                              set(topics) or None, Tape(PENDING))
        self.recordings[recording.id] = recording
        try:
            await self.subscribe_new()  # at once: the first take has the topics there now
        except LaunchError:
            del self.recordings[recording.id]
            raise
        self._follow()
        return {"recording": recording.id, "named": sorted(recording.topics or ()),
                "topics": self._recorded(recording)}

    def _recorded(self, recording: Recording) -> list[str]:
        return sorted(t for t in self.channels
                      if recording.topics is None or t in recording.topics)

    def _recording(self, ident: int) -> Recording:
        # not "id": a request's own id is the reply's
        recording = self.recordings.get(ident)
        if recording is None:
            raise LaunchError(f"no recording {ident!r} in this session")
        return recording

    async def record_take(self, request: RecordTake, client: int) -> dict[str, Any]:
        """The messages since the last take (waiting TAKE_WAIT for some), the channels new
        to the client, the count dropped, the topics waited for."""
        from .tape import LOG_TYPE, OUTPUT_TOPIC, Channel

        recording = self._recording(request.recording)
        tape = recording.tape
        loop = asyncio.get_running_loop()
        wait = TAKE_WAIT if request.wait is None else request.wait
        deadline = loop.time() + min(wait, TAKE_WAIT)
        while not tape.records and loop.time() < deadline:
            await asyncio.sleep(0.05)
        records, dropped = tape.take(TAKE_BYTES)
        channels = []
        # the output's channel first, lines or not: a file's reader finds it where it looks
        for topic in dict.fromkeys([OUTPUT_TOPIC, *(r[0] for r in records)]):
            if topic in recording.told:
                continue
            recording.told.add(topic)
            channel = self.channels.get(topic) if topic != OUTPUT_TOPIC else \
                Channel(OUTPUT_TOPIC, LOG_TYPE, _log_definition())
            if channel is not None:
                channels.append(channel.to_dict())
        waiting = sorted((recording.topics or set()) - set(self.channels))
        return {"channels": channels, "dropped": dropped,
                "messages": [[t, n, base64.b64encode(d).decode("ascii")]
                             for t, n, d in records],
                "waiting": {t: self.unrecorded.get(t, "no publisher yet") for t in waiting}}

    async def record_stop(self, request: RecordStop, client: int) -> dict[str, Any]:
        self.recordings.pop(request.recording, None)
        return {}

    # --- the black box -------------------------------------------------------------------------

    def _box_on(self, seconds: float, size: int) -> None:
        from .tape import LOG_TYPE, OUTPUT_TOPIC, Channel, Tape

        if not seconds > 0 or not size > 0:
            raise ValueError(f"the black box needs a positive number of seconds and bytes "
                             f"(got {seconds:g} s, {size} bytes)")
        if self.box is None:
            self.box = Tape(size, seconds)
            self.box.channel(Channel(OUTPUT_TOPIC, LOG_TYPE, _log_definition()))
        else:
            self.box.max_bytes, self.box.window_ns = size, int(seconds * 1e9)
        self.box_seconds = seconds

    def status(self) -> dict[str, Any]:
        box = self.box
        return {"on": box is not None, "seconds": self.box_seconds,
                "size": box.max_bytes if box else 0, "bytes": box.size if box else 0,
                "messages": len(box.records) if box else 0,
                "topics": sorted(self.channels), "files": list(self.files)}

    async def black_box(self, request: BlackBox, client: int) -> dict[str, Any]:
        """`{"seconds": S, "size": B}` switches it on (or changes it), `{"seconds": 0}` off,
        nothing: how it is."""
        if request.seconds is not None:
            seconds = request.seconds
            if seconds == 0:
                self.box = None
            else:
                self._box_on(seconds, request.size or DEFAULT_SIZE)
                self._follow()
        return self.status()

    async def black_box_write(self, request: BlackBoxWrite, client: int) -> dict[str, Any]:
        if self.box is None:
            raise LaunchError("the black box is off: start the launch with --black-box "
                              "SECONDS, or switch it on (tuilaunch record NAME --black-box-on "
                              "SECONDS)")
        path, count = await self._write("now")
        return {"path": path, "messages": count}

    async def _write(self, why: str) -> tuple[str, int]:
        from .mcap_out import write_file

        box = self.box
        assert box is not None
        for channel in self.channels.values():
            box.channel(channel)
        channels, records = box.snapshot(time.time_ns())
        stem = f"black-box-{why}-{time.strftime('%Y%m%d-%H%M%S')}"
        path, count = await asyncio.to_thread(write_file, self.supervisor.log_dir, stem,
                                              channels, records)
        self.files.append(str(path))
        return str(path), count

    async def _write_after_death(self, process: str) -> None:
        last = self.written.get(process)
        now = time.monotonic()
        if last is not None and now - last[0] < ONE_FILE_PER:
            self.supervisor.emit(Log(process, level="WARN", reason=(
                f"black box not written again within a minute (crash loop): the last is "
                f"{last[1]}")))
            return
        self.written[process] = (now, "")
        await asyncio.sleep(AFTER_DEATH)
        if self.box is None:
            return
        try:
            path, count = await self._write(process)
        except OSError as exc:
            self.supervisor.emit(Log(process, level="ERROR",
                                     reason=f"black box not written: {exc}"))
            return
        self.written[process] = (now, path)
        # its detail (the tree's row, the detail line) and a line of its pane and launch.log
        self.supervisor.emit(Log(process, level="WARN", reason=(
            f"black box written: {path} (the last {self.box_seconds:g} s, "
            f"{count} messages)"), data={"detail": f"black box {path}"}))


def _full_name(info: Any) -> str:
    namespace = info.node_namespace.rstrip("/")
    return f"{namespace}/{info.node_name}"


def _log_definition() -> str:
    from .definitions import full_definition
    from .tape import LOG_TYPE

    return full_definition(LOG_TYPE) or LOG_FALLBACK


LOG_FALLBACK = """uint8 DEBUG=10
uint8 INFO=20
uint8 WARN=30
uint8 ERROR=40
uint8 FATAL=50
builtin_interfaces/Time stamp
uint8 level
string name
string msg
string file
string function
uint32 line
================================================================================
MSG: builtin_interfaces/Time
int32 sec
uint32 nanosec
"""
"""rcl_interfaces/msg/Log's fields where the package's .msg is not installed: the output
channel is always readable."""


__all__ = ["BLACK_BOX_ENV", "Recorder", "black_box_env"]
