"""`RemoteSupervisor`, which the TUI uses exactly as it uses an in-process Supervisor, served
by a session server.

The TUI process then never reads a node's pipe: a flood is read, logged and batched by the
server, and reaches the UI as one message per batch.

A session on another machine (`host`) is reached over ssh (engine/run/machines/remote.py); its log
files are read through the server (`read_log`). When that link drops, the launch there runs
on: this client says so, reconnects with backoff (or at once when asked), and then delivers
what happened meanwhile, from where it left off: the lines from the log files (counted
from the offsets of its last subscription, so none is seen twice or missed) and the state
events the server kept, in time order (relinking.py).

A port over one Connection (engine/run/session/connection.py: the greeting, request
numbers, replies matched), its Reconnector (the attempts and their pace) and its Gaps
(gaps.py: where its view of each log file stands, and the lines a gap holds, read back
through the server). What keeps a state of its own lives next door: session_state.py
(what the events told: states, pids, ends, the plan, the history; the LaunchPort members
read it), watches.py (the inspector's streams, asked again on a new connection) and
remote_lifecycle.py; link.py sends the teardown's one request.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import time
from pathlib import Path
from typing import Any, TypeVar

from ..engine.plan.model import Plan, PlanDiff
from ..engine.plan.session import Session
from ..engine.run.events import Event
from ..engine.run.machines.remote import RemoteError, RemoteLink
from ..engine.run.session import session_dir
from ..engine.run.session.connection import Connection
from ..engine.run.session.log_reader import LAUNCH_LOG
from ..engine.run.session.protocol import ProtocolError, Stamps
from ..engine.run.session.reconnector import RETRY_FIRST, RETRY_MOST, Reconnector
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary import requests as rq
from ..engine.run.vocabulary.forward import Forward
from ..engine.run.vocabulary.request import Request
from .gaps import Gaps
from .history import merged
from .inspect.watches import Watches
from .link import ANSWER_TIMEOUT, not_answering, send_once
from .port import VERBS, Verb
from .read_only import check_request
from .relinking import relink, ssh_connection
from .remote_lifecycle import RemoteLifecycle
from .served_session import ServedSession
from .session_state import Consumer, SessionState

R = TypeVar("R")

LINK_INTERVAL = 1.0
"""Seconds between event batches for a display over an ssh link: its output pane repaints
once a second anyway (tui PANE_FPS), and every batch costs the link a packet."""
PROBE_AFTER = 2.0
"""Seconds without a word over a link after which the other side is asked something that
is answered at once (a quiet session sends nothing): a link that hangs (no bytes, no
error; ssh says so only after 15 s) shows as silence within a few seconds."""


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
        self.stamps_shown = False
        """Whether the screen shows ROS stamps (time column, raw format): over a link,
        without them the server leaves them out and keeps them (`read_stamps`)."""
        self.watches = Watches()  # the inspector's streams: a new connection asks again
        self.session = session
        self.info = connection.info
        self.log_dir = Path(self.info["log_dir"])
        self.state = SessionState(session, self.gaps, RemoteLifecycle(self.request),
                                  remote=host is not None)
        """What the events told of the session (session_state.py): the members below
        that a frontend reads of it are that object's."""
        self.detached = False
        self.lost = False  # the server vanished without saying it ended
        self.killed_server = False  # "kill now" found it not answering, and SIGKILLed it
        self.owner = False  # started this session in the foreground
        self.keep_on_hangup = False
        self.read_only = False
        """A view that changes nothing: every request that would is refused here, with
        one line (client/read_only.py), before it is sent."""
        self.stopping = False  # asked the session to stop: its end is no loss

    # what a frontend reads of the session (client/port.py), as the events told it
    states = Forward[dict[str, str]]("state")
    pids = Forward[dict[str, int]]("state")
    exit_codes = Forward[dict[str, int]]("state")
    reasons = Forward[dict[str, str]]("state")
    crashed = Forward[dict[str, str]]("state")
    shutdown_reason = Forward[str | None]("state")
    history = Forward[list[Event]]("state")
    lifecycle = Forward[RemoteLifecycle]("state")
    plan = Forward[Plan]("session")
    scrollback = Forward[int]("gaps")

    # what a status line reads of a lost link (client/port.py), the reconnector's
    link_lost = Forward[str | None](
        "relink", "down", "While the link to `host` is down: why (\"link to HOST lost (reason)\").")
    lost_reason = Forward[str | None](
        "relink", "reason", "While it is down: the latest attempt's reason (the first is the "
        "drop's).")
    attempt = Forward[int]("relink")
    attempt_since = Forward[float | None]("relink")

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
            result = await asyncio.wait_for(conn.call(rq.Subscribe(max_lines, interval)),
                                            ANSWER_TIMEOUT)
        except TimeoutError:
            conn.close()
            raise not_answering(name, ANSWER_TIMEOUT) from None
        except (ProtocolError, ConnectionError) as exc:
            conn.close()
            raise SessionError(f"session {name}: {exc}") from None
        if isinstance(session, ServedSession):  # the plan that runs, not the file's
            session.connect(self.request, asyncio.get_running_loop())
        try:
            await self.state.begin(result, conn, ANSWER_TIMEOUT)
        except (TimeoutError, ProtocolError, ConnectionError) as exc:
            conn.close()
            raise SessionError(f"session {name} did not send its plan ({exc or 'timeout'})")\
                from None
        await self.state.replay(result, conn, self.log_dir)
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
            if isinstance(session, ServedSession):
                session.connect(self.request, asyncio.get_running_loop())
            await self.state.begin(result, conn, ANSWER_TIMEOUT * 3)
            await self.state.replay(result, conn, self.log_dir)
        except (TimeoutError, ProtocolError, ConnectionError) as exc:
            conn.close()
            await asyncio.get_running_loop().run_in_executor(None, link.close)
            raise RemoteError(f"{host}: session {name} did not answer ({exc or 'timeout'})")\
                from None
        return self

    async def _subscribe(self) -> dict[str, Any]:
        """Subscribes on the current connection; from here on lines are counted from the
        log files' sizes it answers with."""
        # fair: with a screenful a second, a loud node must not hide the others' lines
        result: dict[str, Any] = await self.conn.call(rq.Subscribe(
            max_lines=self.max_lines, interval=self.interval, fair=True, only=self.only,
            plain=True, stamps=self.stamps_shown))
        self.gaps.subscribed(result["offsets"])
        return result

    # --- the Supervisor's interface ----------------------------------------------------------

    def subscribe(self, consumer: Consumer) -> None:
        self.state.consumers.append(consumer)

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
                    self.state.say(f"lost the connection to session "
                                      f"{self.name}", "ERROR")
                    break
                if not await relink(self, self.host, RETRY_FIRST):
                    if self.stopping and not self.lost:
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
                    await self.state.fetch_plan(self.conn)
                except (ConnectionError, ProtocolError):
                    # not taken: the reconnection reads its lines and events from the gap
                    return None
                except SessionError as exc:
                    self.state.say(str(exc), "ERROR")
            if kind == "events":
                self.state.stamps = Stamps()  # each batch's stamps count from its first
                events = message.get("events") or []
                if not any(data.get("kind") == "view" for data in events):
                    self.state.take(message)
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
                            self.state.say(str(exc), "ERROR")
                    else:
                        self.state.take({"events": [data]})
            elif kind == "ended":
                return int(message.get("status") or 0)

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
            await self._request(rq.SetView(only=process))

    async def _switched(self, only: str | None, offsets: dict[str, int]) -> None:
        """A `view` event: the lines of the pane now shown that were not sent (gaps.py)."""
        lines, notes = await self.gaps.switched(
            only, offsets, [p.id for p in self.plan.processes], self.conn.call)
        for event in notes + merged(lines, []):
            self.state.deliver(event)

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
                self.conn.send(rq.ReadLog(LAUNCH_LOG, limit=0))  # its reply is passed over

    def retry_now(self) -> None:
        """Reconnect at once instead of at the next try (on the loop's thread)."""
        self.relink.now()

    async def catch_up(self) -> list[Event]:
        """Subscribed again after a reconnection (relinking.py): the lines each log file got
        since the last line received (the last `scrollback` of them), and the state events
        after the last one received."""
        start, received = self.gaps.start, self.gaps.received
        result = await self._subscribe()
        await self.state.begin(result, self.conn)
        lines, notes = await self.gaps.missed(start, received, result["offsets"],
                                              self.conn.call)
        recent = self.state.caught_up(result["recent"])
        # the pane shown may have changed while the link was down: read what it lacks
        await self._switched(self.only, result["offsets"])
        return notes + merged(lines, recent)

    async def read_stamps(self, shown: bool, since: int | None,
                          ) -> tuple[int, int, dict[int, int]]:
        """The ROS stamps the server kept of the output lines it sent without them, from
        line `since` on (numbered as in their events' data "line"; None: none wanted), and
        whether the batches from here carry them (`shown`): (the first line whose stamp
        could be read, the line after the last, {line: ms}). Lines of an earlier
        connection are the server's no longer."""
        self.stamps_shown = shown
        before = self.gaps.lines_before
        result = await self._request(rq.ReadStamps(
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
        await self._request(rq.Start(process_id))

    async def stop(self, process_id: str) -> None:
        await self._request(rq.Stop(process_id))

    async def restart(self, process_id: str, prefix: str | None = None,
                      log_level: str | None = None, terminal: bool = False) -> None:
        """As Supervisor.restart: `prefix` runs it under a tool, `terminal` gives it a
        terminal, until a plain restart."""
        await self._request(rq.Restart(process_id, prefix, log_level, terminal))

    async def shutdown(self, reason: str = "shutdown") -> None:
        self.stopping = True
        await self._request(rq.ShutdownLaunch(reason=reason))

    async def run_action(self, action_id: str) -> None:
        await self._request(rq.RunAction(action=action_id))

    async def replace_plan(self, plan: Plan) -> PlanDiff:
        """Relaunches with the session's accepted arguments (the plan was resolved from them);
        the server serialises relaunches and tells every client."""
        result = await self._request(rq.Apply(arguments=self.session.arguments))
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
            if self.stopping and self.link_lost is None and not self.conn.closing:
                self.conn.send(rq.Kill())
            return
        if self.stopping:
            if not send_once(self.name, rq.Kill()):
                self._kill_server()
        elif self.owner and not self.keep_on_hangup and not self.detached:
            send_once(self.name, rq.ShutdownLaunch("the UI ended"))

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

