"""`RemoteSupervisor`, which the TUI uses exactly as it uses an in-process Supervisor, served
by a session server.

The TUI process then never reads a node's pipe: a flood is read, logged and batched by the
server, and reaches the UI as one message per batch.

A session on another machine (`host`) is reached over ssh (engine/run/machines/remote.py); its log
files are read through the server (`read_log`). When that link drops, the launch there runs
on: this client says so, reconnects with backoff (or at once when asked), and then delivers
what happened meanwhile, from where it left off: the lines from the log files (counted
from the offsets of its last subscription, so none is seen twice or missed) and the state
events the server kept, in time order.

Over 500 lines on purpose: reconnecting (`_relink`, `_missed`) swaps this client's own
connection and rewinds its counters, so it stays inside the class, not in a module that
would reach into its private state. What keeps a state of its own lives next door:
watches.py (the inspector's streams, asked again on a new connection) and
remote_lifecycle.py; link.py sends the teardown's one request.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from ..engine.plan.model import Plan, PlanDiff
from ..engine.plan.session import Session
from ..engine.run.events import (
    Dropped,
    Event,
    Failed,
    LifecycleChanged,
    Log,
    Output,
    ProcessExited,
    Relaunched,
    Resources,
    Shutdown,
    Started,
)
from ..engine.run.machines.proxy import SERVER_GONE_WORDS
from ..engine.run.machines.remote import RemoteError, RemoteLink, link_streams, open_remote_streams
from ..engine.run.session import session_dir
from ..engine.run.session.log_reader import LAUNCH_LOG, LogLine, tail_lines
from ..engine.run.session.protocol import (
    MAX_MESSAGE,
    ProtocolError,
    Stamps,
    VersionMismatch,
    check_hello,
    decode,
    encode,
    event_from_dict,
)
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary.request import Request, to_message
from ..engine.run.vocabulary.requests import (
    Apply,
    GetPlan,
    Kill,
    ReadLog,
    ReadStamps,
    Restart,
    RunAction,
    SetView,
    ShutdownLaunch,
    Start,
    Stop,
    Subscribe,
)
from .history import merged
from .link import ANSWER_TIMEOUT, not_answering, send_once
from .port import VERBS, Verb
from .read_only import check_request
from .remote_lifecycle import RemoteLifecycle
from .served_session import ServedSession
from .watches import Watches

Consumer = Callable[[Event], None]
R = TypeVar("R")

RETRY_FIRST = 1.0
"""Seconds before the first try to reconnect a dropped link; doubled after each failure."""
LINK_INTERVAL = 1.0
"""Seconds between event batches for a display over an ssh link: its output pane repaints
once a second anyway (tui PANE_FPS), and every batch costs the link a packet."""
RETRY_MOST = 15.0
"""The longest wait between tries: a robot back on the network is found within this."""
PROBE_AFTER = 2.0
"""Seconds without a word over a link after which the other side is asked something that
is answered at once (a quiet session sends nothing): a link that hangs (no bytes, no
error; ssh says so only after 15 s) shows as silence within a few seconds."""


def merged_usage(held: dict[str, Any], moved: dict[str, Any]) -> dict[str, Any]:
    """The figures held, with the ones a `resources` event says moved. A process whose
    figures are all None has stopped, and is left out; one whose figures are not shown
    (watch_resources `processes`: None figures) keeps its growing-memory mark."""
    usage = dict(held)
    for process, figures in moved.items():
        if isinstance(figures, dict):
            usage[process] = {**usage.get(process, {}), **figures}
    return {p: f for p, f in usage.items() if f.get("rss_bytes") is not None
            or f.get("growing")}


async def _reply_to(reader: asyncio.StreamReader, request_id: int) -> dict[str, Any]:
    """The reply to a request, passing over what the server sends before it."""
    while True:
        line = await reader.readline()
        if not line:
            raise ProtocolError("the server closed the connection")
        message = decode(line)
        if message.get("type") == "reply" and message.get("id") == request_id:
            return message


class RemoteSupervisor:
    """The Supervisor's interface, served by a session server.

    Its coroutines run on the caller's loop (the TUI's engine thread). `states` follows the
    server's; `history` is what happened before this client came: the tail of each log file
    and recent state events, in time order, for the panes to show first."""

    def __init__(self, name: str, session: Session, reader: asyncio.StreamReader,
                 writer: asyncio.StreamWriter, info: dict[str, Any], host: str | None = None,
                 link: RemoteLink | None = None) -> None:
        """`host` and `link`: a session on another machine, over this ssh link."""
        self.name = name
        self.host = host
        self.link = link
        self.link_lost: str | None = None
        """While the link to `host` is down: why ("link to HOST lost (reason)")."""
        self.lost_reason: str | None = None
        """While it is down: why, the latest attempt's reason (the first is the drop's)."""
        self.attempt = 0
        """While it is down: the attempt to reconnect under way (or the last), from 1."""
        self.attempt_since: float | None = None
        """When the attempt under way began (time.monotonic); None between attempts: one
        that hangs (ssh's 15 s, then the greeting's 30) is said as under way, not as the
        reason before it."""
        self.last_heard = time.monotonic()
        """When the other side last sent anything (a link's silence is shown from it)."""
        self._probed = 0.0  # when the last probe was sent
        self.scrollback = 5000
        self.max_lines = 0
        self.interval = 0.0
        self._early: list[dict[str, Any]] = []  # messages read while awaiting a reply
        # where this client's view of each log file stands: the size at subscription,
        # and the lines received (or dropped for it) since
        self._from: dict[str, int] = {}
        self._received: dict[str, int] = {}
        self._last_event = 0.0  # the time of the latest state event received
        self.only: str | None = None
        """The process whose output this client's screen shows (None: all): the server
        sends no other process's lines, read from its log file when shown (`show`)."""
        self._stream_only: str | None = None  # `only` as of the last event received
        self._hidden: dict[str, int] = {}
        """Processes not shown, and the byte of their log file from which their lines were
        not sent: read from there when they are shown again."""
        self._usage: dict[str, Any] = {}  # the figures of `resources`, which sends changes
        self._stamps = Stamps()  # the current batch's output stamps
        self.stamps_shown = False
        """Whether the screen shows ROS stamps (time column, raw format): over a link,
        without them the server leaves them out and keeps them (`read_stamps`)."""
        # output lines received on this connection, and on the ones before it: a line's
        # number in the stream (its event's data "line"), by which its stamp is read
        self._lines_here = 0
        self._lines_before = 0
        self._retry: asyncio.Event | None = None
        self.watches = Watches()  # the inspector's streams: a new connection asks again
        self.session = session
        self.info = info
        self.log_dir = Path(info["log_dir"])
        self.states: dict[str, str] = {}
        self.pids: dict[str, int] = {}  # from the started events, those replayed too
        self.exit_codes: dict[str, int] = {}
        self.reasons: dict[str, str] = {}
        """How each process last ended or failed to start (`exit code 1`, `killed by
        SIGSEGV`), as the server said it: what the shell is told after a failed run."""
        self.crashed: dict[str, str] = {}
        """How each process last died unasked (a crash a respawn outlived too): the exit
        status counts them, so the shell is told of them after the run."""
        self.shutdown_reason: str | None = None
        """Why the session began to stop, as its server said (`tuilaunch stop`, another
        client's quit, a signal): a client that did not ask says it before leaving."""
        self.consumers: list[Consumer] = []
        self.history: list[Event] = []
        self.detached = False
        self.lost = False  # the server vanished without saying it ended
        self.killed_server = False  # "kill now" found it not answering, and SIGKILLed it
        self.owner = False  # started this session in the foreground
        self.keep_on_hangup = False
        self.read_only = False
        """A view that changes nothing: every request that would is refused here, with
        one line (client/read_only.py), before it is sent."""
        self._reader = reader
        self._writer = writer
        self._replies: dict[int, asyncio.Future[Any]] = {}
        self._next_id = 0
        self._stopping = False
        self.lifecycle = RemoteLifecycle(self.request)

    @classmethod
    async def open(cls, name: str, session: Session, scrollback: int = 5000,
                   max_lines: int = 0, interval: float = 0.0) -> RemoteSupervisor:
        """Connects and subscribes; `max_lines` and `interval` bound what a display is sent
        (what it could not draw anyway is counted, not sent)."""
        try:
            reader, writer = await asyncio.open_unix_connection(
                str(session_dir.socket_path(name)), limit=MAX_MESSAGE)
        except OSError as exc:
            raise SessionError(f"session {name} does not answer ({exc.strerror or exc})")\
                from None
        try:
            hello = decode(await asyncio.wait_for(reader.readline(), ANSWER_TIMEOUT))
            try:
                info = check_hello(hello, name)
            except SessionError:
                writer.close()
                raise
            self = cls(name, session, reader, writer, info)
            writer.write(encode(to_message(Subscribe(max_lines, interval), 0)))
            await asyncio.wait_for(writer.drain(), ANSWER_TIMEOUT)
            message = await asyncio.wait_for(_reply_to(reader, 0), ANSWER_TIMEOUT)
        except TimeoutError:
            writer.close()
            raise not_answering(name, ANSWER_TIMEOUT) from None
        except ProtocolError as exc:
            writer.close()
            raise SessionError(f"session {name}: {exc}") from None
        result = message["result"]
        self.states = dict(result["states"])
        self.lifecycle.states.update(result.get("lifecycle") or {})
        if isinstance(session, ServedSession):  # the plan that runs, not the file's
            session.connect(self.request, asyncio.get_running_loop())
            try:
                await asyncio.wait_for(self._fetch_plan(), ANSWER_TIMEOUT)
            except (TimeoutError, ProtocolError, ConnectionError) as exc:
                writer.close()
                raise SessionError(f"session {name} did not send its plan ({exc or 'timeout'})")\
                    from None
        self._adopt(result["arguments"])
        self.history = self._replay(result["offsets"], result["recent"], scrollback)
        self._note_ends(self.history)
        return self

    @classmethod
    async def open_remote(cls, host: str, name: str, session: Session, scrollback: int = 5000,
                          max_lines: int = 0, interval: float = 0.0,
                          link: RemoteLink | None = None) -> RemoteSupervisor:
        """The same over an ssh link to `host` (`link`: one already open, else a new one;
        RemoteError with one line when it cannot be made); the replay is read through the
        server, the files being over there."""
        if link is None:
            link, reader, writer = await open_remote_streams(host, name)
        else:
            reader, writer = await link_streams(link)
        self = cls(name, session, reader, writer, link.hello["info"], host, link)
        self.scrollback, self.max_lines, self.interval = scrollback, max_lines, interval
        try:
            result = await asyncio.wait_for(self._subscribe(), ANSWER_TIMEOUT * 3)
            self.states = dict(result["states"])
            self.lifecycle.states.update(result.get("lifecycle") or {})
            if isinstance(session, ServedSession):
                session.connect(self.request, asyncio.get_running_loop())
                await asyncio.wait_for(self._fetch_plan(), ANSWER_TIMEOUT * 3)
            self._adopt(result["arguments"])
            lines = {}
            for process, end in result["offsets"].items():
                page = await self._call(ReadLog(process=process, end=end, limit=scrollback,
                                                tail=True))
                lines[process] = [LogLine(*line) for line in page["lines"]]
        except (TimeoutError, ProtocolError, ConnectionError) as exc:
            writer.close()
            await asyncio.get_running_loop().run_in_executor(None, link.close)
            raise RemoteError(f"{host}: session {name} did not answer ({exc or 'timeout'})")\
                from None
        self.history = merged(lines, result["recent"])
        self._note_ends(self.history)
        self._note_recent(result["recent"])
        return self

    async def _subscribe(self) -> dict[str, Any]:
        """Subscribes on the current connection; from here on lines are counted from the
        log files' sizes it answers with."""
        # fair: with a screenful a second, a loud node must not hide the others' lines
        result: dict[str, Any] = await self._call(Subscribe(max_lines=self.max_lines,
                                                            interval=self.interval, fair=True,
                                                            only=self.only, plain=True,
                                                            stamps=self.stamps_shown))
        self._lines_before += self._lines_here
        self._lines_here = 0
        self._from = dict(result["offsets"])
        self._received = {}
        self._usage = {}
        return result

    async def _call(self, request: Request[R]) -> R:
        """A request answered before `run` reads the connection (opening, reconnecting):
        what the server sends meanwhile is kept for `run`, in order."""
        self._next_id += 1
        request_id = self._next_id
        self._writer.write(encode(to_message(request, request_id)))
        await self._writer.drain()
        while True:
            line = await self._reader.readline()
            if not line:
                raise ConnectionError(f"the link closed during {request.op}")
            message = decode(line)
            if message.get("type") == "reply" and message.get("id") == request_id:
                if not message.get("ok"):
                    raise SessionError(f"session {self.name}: {message.get('error')}")
                return request.reply(message.get("result"))
            self._early.append(message)

    def _note_ends(self, events: list[Event]) -> None:
        """How processes ended before this client came (the server's recent events)."""
        for event in events:
            self._note_pid(event)
            if isinstance(event, (ProcessExited, Failed)) and event.process and event.reason:
                self.reasons[event.process] = event.reason
            if isinstance(event, ProcessExited) and event.process:
                self._note_crash(event)

    def _note_recent(self, recent: list[dict[str, Any]]) -> None:
        for data in recent:
            self._last_event = max(self._last_event, float(data.get("time") or 0.0))

    @property
    def plan(self) -> Plan:
        return self.session.plan

    async def _fetch_plan(self) -> None:
        """The plan the server runs, for a session whose file is read there (ServedSession);
        before `run` reads the connection, or from `run` itself."""
        assert isinstance(self.session, ServedSession)
        self.session.adopt(await self._call(GetPlan()))

    def _adopt(self, arguments: dict[str, str], relaunched: bool = False) -> None:
        """Another client relaunched with these values: resolve the same plan here.
        `relaunched`: the server read the launch file again, so it is read here too (an
        edited file with the same values is a relaunch as well)."""
        if isinstance(self.session, ServedSession) or (
                arguments == self.session.arguments and not relaunched):
            return
        preview = self.session.preview(arguments, reread=relaunched)
        if preview.plan is not None:
            self.session.accept(preview)

    def _replay(self, offsets: dict[str, int], recent: list[dict[str, Any]],
                scrollback: int) -> list[Event]:
        return merged({process: tail_lines(self.log_dir / f"{process}.log", end, scrollback)
                        for process, end in offsets.items()}, recent)

    # --- the Supervisor's interface ----------------------------------------------------------

    def subscribe(self, consumer: Consumer) -> None:
        self.consumers.append(consumer)

    async def run(self, keep_alive: bool = True) -> int:
        """Delivers the server's events until it ends (its status) or this client detaches;
        a dropped ssh link is reconnected meanwhile (see the module's docstring)."""
        status = 1
        self._retry = asyncio.Event()
        probe = asyncio.ensure_future(self._probe()) if self.host is not None else None
        try:
            while True:
                ended = await self._follow()
                if ended is not None:
                    status = ended
                    break
                if self.detached or self.killed_server:
                    break
                if self.host is None or self.link is None:
                    self.lost = True
                    self._deliver(Log(reason=f"lost the connection to session "
                                      f"{self.name}", level="ERROR"))
                    break
                if not await self._relink():
                    if self._stopping and not self.lost:
                        status = 0  # the stop asked for finished while the link was down
                    break
        finally:
            if probe is not None:
                probe.cancel()
            self._fail_replies(f"session {self.name} is gone")
            self._writer.close()
            if self.link is not None:
                await asyncio.get_running_loop().run_in_executor(None, self.link.close)
        return 0 if self.detached else status

    async def _follow(self) -> int | None:
        """The server's messages until it ends (its status) or the connection closes."""
        while True:
            if self._early:
                message = self._early.pop(0)
            else:
                try:
                    line = await self._reader.readline()
                except (ConnectionError, ValueError):
                    line = b""
                if not line:
                    return None
                self.last_heard = time.monotonic()
                try:
                    message = decode(line)
                except ProtocolError:
                    continue
            kind = message.get("type")
            if kind == "events" and isinstance(self.session, ServedSession) and any(
                    data.get("kind") == "relaunched" for data in message.get("events") or []):
                # the plan the relaunch made is the server's to send, before the event
                # that has the TUI draw it
                try:
                    await self._fetch_plan()
                except (ConnectionError, ProtocolError):
                    # not taken: the reconnection reads its lines and events from the gap
                    return None
                except SessionError as exc:
                    self._deliver(Log(reason=str(exc), level="ERROR"))
            if kind == "events":
                self._stamps = Stamps()  # each batch's stamps count from its first
                events = message.get("events") or []
                if not any(data.get("kind") == "view" for data in events):
                    self._take(message)
                    continue
                # the screen switched panes there: what the pane now shown was not sent
                # is read from the log files at that point of the stream
                self.states.update(message.get("states") or {})
                for data in events:
                    if data.get("kind") == "view":
                        try:
                            await self._switched(data.get("process"),
                                                 (data.get("data") or {}).get("offsets") or {})
                        except (ConnectionError, ProtocolError):
                            return None  # the reconnection reads the gap
                        except SessionError as exc:
                            self._deliver(Log(reason=str(exc), level="ERROR"))
                    else:
                        self._take({"events": [data]})
            elif kind == "reply":
                future = self._replies.pop(message.get("id", -1), None)
                if future is not None and not future.done():
                    future.set_result(message)
            elif kind == "ended":
                return int(message.get("status") or 0)

    def _take(self, message: dict[str, Any]) -> None:
        self.states.update(message.get("states") or {})
        for data in message.get("events") or []:
            if "stamps" in data:
                self._stamps.unpack(data)
            event = event_from_dict(data)
            if isinstance(event, Output) and event.process:
                self._count(event.process, len(event.lines))
                if self.host is not None:  # only a link's stream leaves stamps out
                    event.data = {**(event.data or {}),
                                  "line": self._lines_before + self._lines_here}
                    self._lines_here += len(event.lines)
            elif isinstance(event, Dropped) and event.process:
                # in the file, not sent to us: where, for a display to read them back
                event.data = self._where(event.process)
                self._count(event.process, event.code or 0)
            else:
                self._last_event = max(self._last_event, event.time)
            if isinstance(event, Relaunched):
                self._adopt(dict(item.split(":=", 1) for item in event.lines), True)
            self._note_pid(event)
            if isinstance(event, ProcessExited) and event.process and event.code is not None:
                self.exit_codes[event.process] = event.code
                self._note_crash(event)
            if isinstance(event, (ProcessExited, Failed)) and event.process and event.reason:
                self.reasons[event.process] = event.reason
            if isinstance(event, Shutdown):
                self.shutdown_reason = event.reason or "stop requested"
            if isinstance(event, LifecycleChanged) and event.process:
                self.lifecycle.follow(event.process, event.reason or "")
            if isinstance(event, Resources):
                self._usage = merged_usage(self._usage, event.data or {})
                event.data = dict(self._usage)  # the consumers get them all
            self._deliver(event)

    # --- the pane shown ------------------------------------------------------------------

    async def show(self, process: str | None) -> None:
        """The screen now shows `process`'s output (None: every process's): the server then
        sends only those lines, and the lines of a pane shown again that it did not send
        are read from its log file (`_switched`, when the switch comes back in the
        stream), so switching panes never misses a line."""
        if process == self.only:
            return
        self.only = process
        if self.link_lost is None:
            await self._request(SetView(only=process))

    def _shown(self, process: str, only: str | None) -> bool:
        return only is None or process == only

    async def _switched(self, only: str | None, offsets: dict[str, int]) -> None:
        """A `view` event: from here the stream carries `only`'s lines; `offsets` are the
        log files' sizes at that instant."""
        before, self._stream_only = self._stream_only, only
        processes = set(offsets) | {p.id for p in self.plan.processes}
        lines: dict[str, list[LogLine]] = {}
        notes: list[Event] = []
        for process in sorted(processes):
            end = offsets.get(process, 0)
            if not self._shown(process, only):
                if self._shown(process, before):
                    self._hidden[process] = end  # its lines from here stay over there
                continue
            if self._shown(process, before) and process not in self._hidden:
                continue  # shown all along: its lines came as events
            begin = self._hidden.pop(process, 0)
            if end > begin:
                page = await self._call(ReadLog(process=process, start=begin, end=end,
                                                limit=self.scrollback, tail=True))
                lines[process] = [LogLine(*line) for line in page["lines"]]
                if page.get("skipped"):
                    notes.append(Dropped(process, code=int(page["skipped"]),
                                         data={"start": begin, "skip": 0}))
            # everything up to `end` is now here; its events from the stream come after it
            self._from[process], self._received[process] = end, 0
        for event in notes + merged(lines, []):
            self._deliver(event)

    def _count(self, process: str, lines: int) -> None:
        self._received[process] = self._received.get(process, 0) + lines

    def _where(self, process: str) -> dict[str, int]:
        """Where the next lines of `process` are in its log file, as a `dropped` event's
        data says (`read_log`'s start and skip): after what this client has been sent."""
        return {"start": self._from.get(process, 0), "skip": self._received.get(process, 0)}

    def _fail_replies(self, why: str) -> None:
        for future in self._replies.values():
            if not future.done():
                future.set_exception(SessionError(why))
        self._replies.clear()

    # --- a dropped link ----------------------------------------------------------------------

    def silent_for(self) -> float:
        """Seconds since the other side of the link last said anything (0 with no link,
        or while it is down: then `link_lost` says more)."""
        if self.host is None or self.link_lost is not None:
            return 0.0
        return max(0.0, time.monotonic() - self.last_heard)

    async def _probe(self) -> None:
        """Over a link: after PROBE_AFTER s of silence, asks what is answered at once (a
        log file's size), so a quiet session answers and a hung link stays silent."""
        while True:
            await asyncio.sleep(PROBE_AFTER / 2)
            now = time.monotonic()
            if self.link_lost is not None or self._writer.is_closing() or \
                    now - self.last_heard < PROBE_AFTER or self._probed > self.last_heard:
                continue  # heard lately, or the last probe is still unanswered
            self._probed = now
            self._next_id += 1  # its reply is read and passed over like any other
            with contextlib.suppress(ConnectionError, OSError):
                self._writer.write(encode(to_message(ReadLog(LAUNCH_LOG, limit=0),
                                                     self._next_id)))

    def retry_now(self) -> None:
        """Reconnect at once instead of at the next try (on the loop's thread)."""
        if self._retry is not None:
            self._retry.set()

    async def _relink(self) -> bool:
        """The link to `host` dropped: reconnect with backoff, then deliver what was missed.
        False when there is nothing to reconnect to (detached, or the session ended)."""
        assert self.host is not None and self.link is not None and self._retry is not None
        loop = asyncio.get_running_loop()
        self._writer.close()
        why = await loop.run_in_executor(None, self.link.why_lost)
        if SERVER_GONE_WORDS in why:
            # the link was up: the proxy there saw the session's server die (kill -9)
            self.lost = not self._stopping
            self._deliver(Log(reason=f"{self.host}: {why.split('error: ', 1)[-1]}",
                              level="ERROR"))
            return False
        self.link_lost = f"link to {self.host} lost ({why})"
        self.lost_reason = why
        self._fail_replies(self.link_lost)
        self._deliver(Log(reason=f"{self.link_lost}; session {self.name} runs on "
                          "there; reconnecting", level="ERROR"))
        delay = RETRY_FIRST
        said = ""
        self.attempt = 0
        while not self.detached:
            self.attempt_since = None
            self._retry.clear()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(self._retry.wait(), delay)
            if self.detached:
                return False
            self.attempt, self.attempt_since = self.attempt + 1, time.monotonic()
            try:
                link, self._reader, self._writer = await open_remote_streams(
                    self.host, self.name)
            except VersionMismatch as exc:
                # another session of that name, of another tuilaunch: not ours to speak to
                self.link_lost = None
                self._deliver(Log(reason=str(exc), level="ERROR"))
                return False
            except RemoteError as exc:
                if "no running session" in str(exc):
                    self.lost = not self._stopping  # unless it was asked to stop
                    self.link_lost = None
                    self._deliver(Log(reason=f"session {self.name} ended on "
                                      f"{self.host} while the link was down", level="ERROR"))
                    return False
                self.lost_reason = str(exc)  # the outage's reason now, not its first
                if str(exc) != said:  # each new reason once, not every try
                    said = str(exc)
                    self._deliver(Log(reason=f"reconnecting: {exc}", level="WARN"))
                delay = min(delay * 2, RETRY_MOST)
                continue
            old, self.link = self.link, link
            await loop.run_in_executor(None, old.close)
            start, received = self._from, self._received
            try:
                missed = await asyncio.wait_for(self._missed(), ANSWER_TIMEOUT * 3)
                await asyncio.wait_for(self.watches.ask_again(self._call, self._warn),
                                       ANSWER_TIMEOUT * 3)
            except (TimeoutError, ConnectionError, ProtocolError, SessionError) as exc:
                # the link dropped again before the gap was read: it is read on the next
                # one, from the same place; what this one sent meanwhile is in that gap
                self._from, self._received = start, received
                self._early.clear()
                self._writer.close()
                self._deliver(Log(reason=f"reconnecting: {exc}", level="WARN"))
                continue
            self.link_lost = self.lost_reason = self.attempt_since = None
            self.last_heard = time.monotonic()
            self._deliver(Log(reason=f"link to {self.host} back: what happened "
                              "meanwhile follows"))
            for event in missed:
                self._deliver(event)
            return True
        return False

    async def _missed(self) -> list[Event]:
        """Subscribes again; the lines each log file got since the last line received (the
        last `scrollback` of them), and the state events after the last one received."""
        start, received = self._from, self._received
        result = await self._subscribe()
        self.states = dict(result["states"])
        self.lifecycle.states.update(result.get("lifecycle") or {})
        if isinstance(self.session, ServedSession):
            await self._fetch_plan()
        self._adopt(result["arguments"])
        lines: dict[str, list[LogLine]] = {}
        notes: list[Event] = []
        for process, end in result["offsets"].items():
            begin, skip = start.get(process, 0), received.get(process, 0)
            if not self._shown(process, self._stream_only) or end <= begin:
                continue  # a pane not shown is read from its file when it is
            page = await self._call(ReadLog(process=process, start=begin, skip=skip, end=end,
                                            limit=self.scrollback, tail=True))
            lines[process] = [LogLine(*line) for line in page["lines"]]
            if page.get("skipped"):  # read back only the last `scrollback` of them
                notes.append(Dropped(process, code=int(page["skipped"]),
                                     data={"start": begin, "skip": skip}))
        recent = [data for data in result["recent"]
                  if float(data.get("time") or 0.0) > self._last_event]
        self._note_recent(recent)
        for data in recent:
            event = event_from_dict(data)
            if isinstance(event, ProcessExited) and event.process and event.code is not None:
                self.exit_codes[event.process] = event.code
                self._note_crash(event)
        # the pane shown may have changed while the link was down: read what it lacks
        await self._switched(self.only, result["offsets"])
        return notes + merged(lines, recent)

    def _note_pid(self, event: Event) -> None:
        if event.process is None:
            return
        if isinstance(event, Started) and event.pid is not None:
            self.pids[event.process] = event.pid
        elif isinstance(event, ProcessExited) or isinstance(event, Failed):
            self.pids.pop(event.process, None)

    def _note_crash(self, event: ProcessExited) -> None:
        """An exit nobody asked for with a non-zero status: the run's exit status is 1."""
        assert event.process is not None
        if event.crashed:
            self.crashed[event.process] = event.reason or f"exit code {event.code}"

    def _deliver(self, event: Event) -> None:
        for consumer in list(self.consumers):
            consumer(event)

    def _warn(self, text: str) -> None:
        self._deliver(Log(reason=text, level="WARN"))

    async def read_stamps(self, shown: bool, since: int | None,
                          ) -> tuple[int, int, dict[int, int]]:
        """The ROS stamps the server kept of the output lines it sent without them, from
        line `since` on (numbered as in their events' data "line"; None: none wanted), and
        whether the batches from here carry them (`shown`): (the first line whose stamp
        could be read, the line after the last, {line: ms}). Lines of an earlier
        connection are the server's no longer."""
        self.stamps_shown = shown
        before = self._lines_before
        result = await self._request(ReadStamps(
            on=shown, since=None if since is None else max(since - before, 0)))
        first = before + int(result.get("first") or 0)
        stamps = Stamps().decode(list(result.get("stamps") or []))
        return first, first + len(stamps), {
            first + index: ms for index, ms in enumerate(stamps) if ms is not None}

    async def request(self, request: Request[R]) -> R:
        """The result of any request of the protocol (vocabulary/requests.py): `Topics`,
        `WatchRates`, `EchoStart`, ...; SessionError with the server's message when it
        fails."""
        result = await self._request(request)
        self.watches.note(request)
        return result

    async def _request(self, request: Request[R]) -> R:
        if self.read_only:
            check_request(request)
        if self.link_lost is not None:
            raise SessionError(f"{self.link_lost}: not sent ({request.op}); reconnecting")
        self._next_id += 1
        future: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        self._replies[self._next_id] = future
        self._writer.write(encode(to_message(request, self._next_id)))
        await self._writer.drain()
        reply = await future
        if not reply.get("ok"):
            raise SessionError(f"session {self.name}: {reply.get('error')}")
        return request.reply(reply.get("result"))

    async def command(self, verb: Verb, process: str) -> None:
        """s, r, t (`tuilaunch stop|restart|start`): one request to the server."""
        await self._request(VERBS[verb](process))

    async def start(self, process_id: str) -> None:
        await self._request(Start(process_id))

    async def stop(self, process_id: str) -> None:
        await self._request(Stop(process_id))

    async def restart(self, process_id: str, prefix: str | None = None,
                      log_level: str | None = None, terminal: bool = False) -> None:
        """As Supervisor.restart: `prefix` runs it under a tool, `terminal` gives it a
        terminal, until a plain restart."""
        await self._request(Restart(process_id, prefix, log_level, terminal))

    async def shutdown(self, reason: str = "shutdown") -> None:
        self._stopping = True
        await self._request(ShutdownLaunch(reason=reason))

    async def run_action(self, action_id: str) -> None:
        await self._request(RunAction(action=action_id))

    async def replace_plan(self, plan: Plan) -> PlanDiff:
        """Relaunches with the session's accepted arguments (the plan was resolved from them);
        the server serialises relaunches and tells every client."""
        result = await self._request(Apply(arguments=self.session.arguments))
        stop, start = list(result["stop"]), list(result["start"])
        return PlanDiff([], stop, start)

    async def detach(self) -> None:
        self.detached = True
        self._writer.close()
        if self._retry is not None:
            self._retry.set()  # a reconnection waiting for its next try gives up

    def kill_all(self) -> None:
        """While a shutdown runs: SIGKILL what is left, now. Otherwise the UI is being torn
        down without a shutdown: a session it started in the foreground (and not told to
        outlive a hang-up) is stopped by its server; others run on."""
        if self.read_only:
            return  # it asked for no shutdown and owns nothing: nothing is its to kill
        if self.host is not None:
            # over there: only the link reaches it, and only "kill now" is ours to send
            if self._stopping and self.link_lost is None and not self._writer.is_closing():
                self._writer.write(encode(to_message(Kill(), 1)))
            return
        if self._stopping:
            if not send_once(self.name, Kill()):
                self._kill_server()
        elif self.owner and not self.keep_on_hangup and not self.detached:
            send_once(self.name, ShutdownLaunch("the UI ended"))

    def _kill_server(self) -> None:
        """"Kill now" and the server does not answer: SIGKILL it; its watchdog then kills
        every process of the launch, which is what the operator asked for."""
        pid = int(self.info.get("pid") or 0)
        if pid > 0:
            try:
                os.kill(pid, signal.SIGKILL)
                self.killed_server = True
            except OSError:
                pass

