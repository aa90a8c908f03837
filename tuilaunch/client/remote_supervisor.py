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

A port over one Connection (engine/run/session/connection.py: the greeting, request
numbers, replies matched), its Reconnector (the attempts and their pace) and its Gaps
(gaps.py: where its view of each log file stands, and the lines a gap holds, read back
through the server). What keeps a state of its own lives next door: watches.py (the
inspector's streams, asked again on a new connection) and remote_lifecycle.py; link.py
sends the teardown's one request.
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
from ..engine.run.machines.remote import RemoteError, RemoteLink, open_remote_link
from ..engine.run.session import session_dir
from ..engine.run.session.connection import Connection
from ..engine.run.session.log_reader import LAUNCH_LOG, LogLine, tail_lines
from ..engine.run.session.protocol import ProtocolError, Stamps, VersionMismatch, event_from_dict
from ..engine.run.session.reconnector import RETRY_FIRST, RETRY_MOST, Reconnector
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary.request import Request
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
from .gaps import Gaps
from .history import merged
from .link import ANSWER_TIMEOUT, not_answering, send_once
from .port import VERBS, Verb
from .read_only import check_request
from .remote_lifecycle import RemoteLifecycle
from .served_session import ServedSession
from .watches import Watches

Consumer = Callable[[Event], None]
R = TypeVar("R")

LINK_INTERVAL = 1.0
"""Seconds between event batches for a display over an ssh link: its output pane repaints
once a second anyway (tui PANE_FPS), and every batch costs the link a packet."""
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


async def ssh_connection(host: str, name: str, link: RemoteLink | None = None,
                         ) -> tuple[RemoteLink, Connection]:
    """A Connection over an ssh link to `host`'s session (`link`: one already open and
    greeted, else a new one; RemoteError with one line when it cannot be made)."""
    if link is None:
        link = await asyncio.get_running_loop().run_in_executor(
            None, lambda: open_remote_link(host, name))
    return link, await Connection.on_socket(link.sock, link.info, name)


class RemoteSupervisor:
    """The Supervisor's interface, served by a session server.

    Its coroutines run on the caller's loop (the TUI's engine thread). `states` follows the
    server's; `history` is what happened before this client came: the tail of each log file
    and recent state events, in time order, for the panes to show first."""

    def __init__(self, name: str, session: Session, connection: Connection,
                 host: str | None = None, link: RemoteLink | None = None) -> None:
        """`host` and `link`: a session on another machine, over this ssh link."""
        self.name = name
        self.host = host
        self.link = link
        self.conn = connection
        self.relink = Reconnector(RETRY_FIRST, RETRY_MOST)
        self._probed = 0.0  # when the last probe was sent
        self.max_lines = 0
        self.interval = 0.0
        self.gaps = Gaps()
        self.only: str | None = None
        """The process whose output this client's screen shows (None: all): the server
        sends no other process's lines, read from its log file when shown (`show`)."""
        self._usage: dict[str, Any] = {}  # the figures of `resources`, which sends changes
        self._stamps = Stamps()  # the current batch's output stamps
        self.stamps_shown = False
        """Whether the screen shows ROS stamps (time column, raw format): over a link,
        without them the server leaves them out and keeps them (`read_stamps`)."""
        self.watches = Watches()  # the inspector's streams: a new connection asks again
        self.session = session
        self.info = connection.info
        self.log_dir = Path(self.info["log_dir"])
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
        self._stopping = False
        self.lifecycle = RemoteLifecycle(self.request)

    # what a status line reads of a lost link (client/port.py), the reconnector's
    @property
    def link_lost(self) -> str | None:
        """While the link to `host` is down: why ("link to HOST lost (reason)")."""
        return self.relink.down

    @property
    def lost_reason(self) -> str | None:
        """While it is down: the latest attempt's reason (the first is the drop's)."""
        return self.relink.reason

    @property
    def attempt(self) -> int:
        return self.relink.attempt

    @property
    def attempt_since(self) -> float | None:
        return self.relink.attempt_since

    @property
    def scrollback(self) -> int:
        return self.gaps.scrollback

    @classmethod
    async def open(cls, name: str, session: Session, scrollback: int = 5000,
                   max_lines: int = 0, interval: float = 0.0) -> RemoteSupervisor:
        """Connects and subscribes; `max_lines` and `interval` bound what a display is sent
        (what it could not draw anyway is counted, not sent)."""
        try:
            conn = await Connection.open_unix(str(session_dir.socket_path(name)), name,
                                              ANSWER_TIMEOUT)
        except TimeoutError:
            raise not_answering(name, ANSWER_TIMEOUT) from None
        self = cls(name, session, conn)
        self.gaps.scrollback, self.max_lines, self.interval = scrollback, max_lines, interval
        try:
            result = await asyncio.wait_for(conn.call(Subscribe(max_lines, interval)),
                                            ANSWER_TIMEOUT)
        except TimeoutError:
            conn.close()
            raise not_answering(name, ANSWER_TIMEOUT) from None
        except (ProtocolError, ConnectionError) as exc:
            conn.close()
            raise SessionError(f"session {name}: {exc}") from None
        self.states = dict(result["states"])
        self.lifecycle.states.update(result.get("lifecycle") or {})
        if isinstance(session, ServedSession):  # the plan that runs, not the file's
            session.connect(self.request, asyncio.get_running_loop())
            try:
                await asyncio.wait_for(self._fetch_plan(), ANSWER_TIMEOUT)
            except (TimeoutError, ProtocolError, ConnectionError) as exc:
                conn.close()
                raise SessionError(f"session {name} did not send its plan ({exc or 'timeout'})")\
                    from None
        self._adopt(result["arguments"])
        self.history = merged({process: tail_lines(self.log_dir / f"{process}.log", end,
                                                   scrollback)
                               for process, end in result["offsets"].items()}, result["recent"])
        self._note_ends(self.history)
        return self

    @classmethod
    async def open_remote(cls, host: str, name: str, session: Session, scrollback: int = 5000,
                          max_lines: int = 0, interval: float = 0.0,
                          link: RemoteLink | None = None) -> RemoteSupervisor:
        """The same over an ssh link to `host` (`link`: one already open, else a new one;
        RemoteError with one line when it cannot be made); the replay is read through the
        server, the files being over there."""
        link, conn = await ssh_connection(host, name, link)
        self = cls(name, session, conn, host, link)
        self.gaps.scrollback, self.max_lines, self.interval = scrollback, max_lines, interval
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
                page = await conn.call(ReadLog(process=process, end=end, limit=scrollback,
                                               tail=True))
                lines[process] = [LogLine(*line) for line in page["lines"]]
        except (TimeoutError, ProtocolError, ConnectionError) as exc:
            conn.close()
            await asyncio.get_running_loop().run_in_executor(None, link.close)
            raise RemoteError(f"{host}: session {name} did not answer ({exc or 'timeout'})")\
                from None
        self.history = merged(lines, result["recent"])
        self._note_ends(self.history)
        self.gaps.heard(result["recent"])
        return self

    async def _subscribe(self) -> dict[str, Any]:
        """Subscribes on the current connection; from here on lines are counted from the
        log files' sizes it answers with."""
        # fair: with a screenful a second, a loud node must not hide the others' lines
        result: dict[str, Any] = await self.conn.call(Subscribe(
            max_lines=self.max_lines, interval=self.interval, fair=True, only=self.only,
            plain=True, stamps=self.stamps_shown))
        self.gaps.subscribed(result["offsets"])
        self._usage = {}
        return result

    def _note_ends(self, events: list[Event]) -> None:
        """How processes ended before this client came (the server's recent events)."""
        for event in events:
            self._note_pid(event)
            if isinstance(event, (ProcessExited, Failed)) and event.process and event.reason:
                self.reasons[event.process] = event.reason
            if isinstance(event, ProcessExited) and event.process:
                self._note_crash(event)

    @property
    def plan(self) -> Plan:
        return self.session.plan

    async def _fetch_plan(self) -> None:
        """The plan the server runs, for a session whose file is read there (ServedSession);
        before `run` reads the connection, or from `run` itself."""
        assert isinstance(self.session, ServedSession)
        self.session.adopt(await self.conn.call(GetPlan()))

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

    # --- the Supervisor's interface ----------------------------------------------------------

    def subscribe(self, consumer: Consumer) -> None:
        self.consumers.append(consumer)

    async def run(self, keep_alive: bool = True) -> int:
        """Delivers the server's events until it ends (its status) or this client detaches;
        a dropped ssh link is reconnected meanwhile (see the module's docstring)."""
        status = 1
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
            self.conn.fail(f"session {self.name} is gone")
            self.conn.close()
            if self.link is not None:
                await asyncio.get_running_loop().run_in_executor(None, self.link.close)
        return 0 if self.detached else status

    async def _follow(self) -> int | None:
        """The server's messages until it ends (its status) or the connection closes."""
        while True:
            message = await self.conn.receive()
            if message is None:
                return None
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
            elif kind == "ended":
                return int(message.get("status") or 0)

    def _take(self, message: dict[str, Any]) -> None:
        self.states.update(message.get("states") or {})
        for data in message.get("events") or []:
            if "stamps" in data:
                self._stamps.unpack(data)
            event = event_from_dict(data)
            if isinstance(event, Output) and event.process:
                self.gaps.count(event.process, len(event.lines))
                if self.host is not None:  # only a link's stream leaves stamps out
                    event.data = {**(event.data or {}),
                                  "line": self.gaps.number(len(event.lines))}
            elif isinstance(event, Dropped) and event.process:
                # in the file, not sent to us: where, for a display to read them back
                event.data = self.gaps.where(event.process)
                self.gaps.count(event.process, event.code or 0)
            else:
                self.gaps.last_event = max(self.gaps.last_event, event.time)
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

    async def _switched(self, only: str | None, offsets: dict[str, int]) -> None:
        """A `view` event: the lines of the pane now shown that were not sent (gaps.py)."""
        lines, notes = await self.gaps.switched(
            only, offsets, [p.id for p in self.plan.processes], self.conn.call)
        for event in notes + merged(lines, []):
            self._deliver(event)

    # --- a dropped link ----------------------------------------------------------------------

    def silent_for(self) -> float:
        """Seconds since the other side of the link last said anything (0 with no link,
        or while it is down: then `link_lost` says more)."""
        if self.host is None or self.link_lost is not None:
            return 0.0
        return max(0.0, time.monotonic() - self.conn.last_heard)

    async def _probe(self) -> None:
        """Over a link: after PROBE_AFTER s of silence, asks what is answered at once (a
        log file's size), so a quiet session answers and a hung link stays silent."""
        while True:
            await asyncio.sleep(PROBE_AFTER / 2)
            now, heard = time.monotonic(), self.conn.last_heard
            if self.link_lost is not None or self.conn.closing or \
                    now - heard < PROBE_AFTER or self._probed > heard:
                continue  # heard lately, or the last probe is still unanswered
            self._probed = now
            with contextlib.suppress(ConnectionError, OSError):
                self.conn.send(ReadLog(LAUNCH_LOG, limit=0))  # its reply is passed over

    def retry_now(self) -> None:
        """Reconnect at once instead of at the next try (on the loop's thread)."""
        self.relink.now()

    async def _relink(self) -> bool:
        """The link to `host` dropped: reconnect with backoff, then deliver what was missed.
        False when there is nothing to reconnect to (detached, or the session ended)."""
        assert self.host is not None and self.link is not None
        loop = asyncio.get_running_loop()
        self.conn.close()
        why = await loop.run_in_executor(None, self.link.why_lost)
        if SERVER_GONE_WORDS in why:
            # the link was up: the proxy there saw the session's server die (kill -9)
            self.lost = not self._stopping
            self._deliver(Log(reason=f"{self.host}: {why.split('error: ', 1)[-1]}",
                              level="ERROR"))
            return False
        self.relink.lost(f"link to {self.host} lost ({why})", why, RETRY_FIRST)
        self.conn.fail(f"link to {self.host} lost ({why})")
        self._deliver(Log(reason=f"{self.link_lost}; session {self.name} runs on "
                          "there; reconnecting", level="ERROR"))
        while not self.detached:
            await self.relink.next_attempt()
            if self.detached:
                return False
            try:
                link, self.conn = await ssh_connection(self.host, self.name)
            except VersionMismatch as exc:
                # another session of that name, of another tuilaunch: not ours to speak to
                self.relink.down = None
                self._deliver(Log(reason=str(exc), level="ERROR"))
                return False
            except RemoteError as exc:
                if "no running session" in str(exc):
                    self.lost = not self._stopping  # unless it was asked to stop
                    self.relink.down = None
                    self._deliver(Log(reason=f"session {self.name} ended on "
                                      f"{self.host} while the link was down", level="ERROR"))
                    return False
                if self.relink.failed(str(exc)):  # each new reason once, not every try
                    self._deliver(Log(reason=f"reconnecting: {exc}", level="WARN"))
                continue
            old, self.link = self.link, link
            await loop.run_in_executor(None, old.close)
            start, received = self.gaps.start, self.gaps.received
            try:
                missed = await asyncio.wait_for(self._missed(), ANSWER_TIMEOUT * 3)
                await asyncio.wait_for(self.watches.ask_again(self.conn.call, self._warn),
                                       ANSWER_TIMEOUT * 3)
            except (TimeoutError, ConnectionError, ProtocolError, SessionError) as exc:
                # the link dropped again before the gap was read: it is read on the next
                # one, from the same place; what this one sent meanwhile is in that gap
                self.gaps.start, self.gaps.received = start, received
                self.conn.forget_early()
                self.conn.close()
                self._deliver(Log(reason=f"reconnecting: {exc}", level="WARN"))
                continue
            self.relink.back()
            self._deliver(Log(reason=f"link to {self.host} back: what happened "
                              "meanwhile follows"))
            for event in missed:
                self._deliver(event)
            return True
        return False

    async def _missed(self) -> list[Event]:
        """Subscribes again; the lines each log file got since the last line received (the
        last `scrollback` of them), and the state events after the last one received."""
        start, received = self.gaps.start, self.gaps.received
        result = await self._subscribe()
        self.states = dict(result["states"])
        self.lifecycle.states.update(result.get("lifecycle") or {})
        if isinstance(self.session, ServedSession):
            await self._fetch_plan()
        self._adopt(result["arguments"])
        lines, notes = await self.gaps.missed(start, received, result["offsets"],
                                              self.conn.call)
        recent = [data for data in result["recent"]
                  if float(data.get("time") or 0.0) > self.gaps.last_event]
        self.gaps.heard(recent)
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
        before = self.gaps.lines_before
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
        return await self.conn.ask(request)

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
        self.conn.close()
        self.relink.now()  # a reconnection waiting for its next try gives up

    def kill_all(self) -> None:
        """While a shutdown runs: SIGKILL what is left, now. Otherwise the UI is being torn
        down without a shutdown: a session it started in the foreground (and not told to
        outlive a hang-up) is stopped by its server; others run on."""
        if self.read_only:
            return  # it asked for no shutdown and owns nothing: nothing is its to kill
        if self.host is not None:
            # over there: only the link reaches it, and only "kill now" is ours to send
            if self._stopping and self.link_lost is None and not self.conn.closing:
                self.conn.send(Kill())
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

