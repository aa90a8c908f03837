"""`RemoteSupervisor`, which the TUI uses exactly as it uses an in-process Supervisor, served
by a session server.

The TUI process then never reads a node's pipe: a flood is read, logged and batched by the
server, and reaches the UI as one message per batch.
"""

from __future__ import annotations

import asyncio
import os
import signal
import socket
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..engine.plan.model import Plan, PlanDiff
from ..engine.plan.session import Session
from ..engine.run import session_dir
from ..engine.run.log_reader import tail_lines
from ..engine.run.output import screen_str
from ..engine.run.protocol import MAX_MESSAGE, ProtocolError, decode, encode, event_from_dict
from ..engine.run.session_dir import SessionError
from ..engine.run.supervisor import Event
from .link import ANSWER_TIMEOUT, not_answering

Consumer = Callable[[Event], None]


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
                 writer: asyncio.StreamWriter, info: dict[str, Any]) -> None:
        self.name = name
        self.session = session
        self.info = info
        self.log_dir = Path(info["log_dir"])
        self.states: dict[str, str] = {}
        self.exit_codes: dict[str, int] = {}
        self.consumers: list[Consumer] = []
        self.history: list[Event] = []
        self.detached = False
        self.lost = False  # the server vanished without saying it ended
        self.killed_server = False  # "kill now" found it not answering, and SIGKILLed it
        self.owner = False  # started this session in the foreground
        self.keep_on_hangup = False
        self._reader = reader
        self._writer = writer
        self._replies: dict[int, asyncio.Future[Any]] = {}
        self._next_id = 0
        self._stopping = False
        self.lifecycle = RemoteLifecycle(self)

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
            self = cls(name, session, reader, writer, hello["info"])
            writer.write(encode({"id": 0, "op": "subscribe", "max_lines": max_lines,
                                 "interval": interval}))
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
        self._adopt(result["arguments"])
        self.history = self._replay(result["offsets"], result["recent"], scrollback)
        return self

    @property
    def plan(self) -> Plan:
        return self.session.plan

    def _adopt(self, arguments: dict[str, str]) -> None:
        """Another client relaunched with these values: resolve the same plan here."""
        if arguments == self.session.arguments:
            return
        preview = self.session.preview(arguments)
        if preview.plan is not None:
            self.session.accept(preview)

    def _replay(self, offsets: dict[str, int], recent: list[dict[str, Any]],
                scrollback: int) -> list[Event]:
        timed: list[tuple[float, int, Event]] = []
        for process, end in offsets.items():
            for line in tail_lines(self.log_dir / f"{process}.log", end, scrollback):
                timed.append((line.time, len(timed), Event(
                    "output", process, stream=line.stream, lines=[screen_str(line.text)],
                    time=line.time)))
        for data in recent:
            event = event_from_dict(data)
            timed.append((event.time, len(timed), event))
        timed.sort(key=lambda item: (item[0], item[1]))
        return _batched([event for _, _, event in timed])

    # --- the Supervisor's interface ----------------------------------------------------------

    def subscribe(self, consumer: Consumer) -> None:
        self.consumers.append(consumer)

    async def run(self, keep_alive: bool = True) -> int:
        """Delivers the server's events until it ends (its status) or this client detaches."""
        status = 1
        try:
            while True:
                try:
                    line = await self._reader.readline()
                except (ConnectionError, ValueError):
                    line = b""
                if not line:
                    if not self.detached and not self.killed_server:
                        self.lost = True
                        self._deliver(Event("log", reason=f"lost the connection to session "
                                            f"{self.name}", level="ERROR"))
                    break
                try:
                    message = decode(line)
                except ProtocolError:
                    continue
                kind = message.get("type")
                if kind == "events":
                    self.states.update(message.get("states") or {})
                    for data in message.get("events") or []:
                        event = event_from_dict(data)
                        if event.kind == "relaunched":
                            self._adopt(dict(item.split(":=", 1) for item in event.lines))
                        if event.kind == "exited" and event.process and event.code is not None:
                            self.exit_codes[event.process] = event.code
                        if event.kind == "lifecycle" and event.process:
                            self.lifecycle.follow(event.process, event.reason or "")
                        self._deliver(event)
                elif kind == "reply":
                    future = self._replies.pop(message.get("id", -1), None)
                    if future is not None and not future.done():
                        future.set_result(message)
                elif kind == "ended":
                    status = int(message.get("status") or 0)
                    break
        finally:
            for future in self._replies.values():
                if not future.done():
                    future.set_exception(SessionError(f"session {self.name} is gone"))
            self._writer.close()
        return 0 if self.detached else status

    def _deliver(self, event: Event) -> None:
        for consumer in list(self.consumers):
            consumer(event)

    async def request(self, op: str, **fields: Any) -> Any:
        """The result of any request of the protocol (engine/run/protocol.py): `topics`,
        `watch_rates`, `echo`, ...; SessionError with the server's message when it fails."""
        return await self._request(op, **fields)

    async def _request(self, op: str, **fields: Any) -> Any:
        self._next_id += 1
        future: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        self._replies[self._next_id] = future
        self._writer.write(encode({"id": self._next_id, "op": op, **fields}))
        await self._writer.drain()
        reply = await future
        if not reply.get("ok"):
            raise SessionError(f"session {self.name}: {reply.get('error')}")
        return reply.get("result")

    async def start(self, process_id: str) -> None:
        await self._request("start", process=process_id)

    async def stop(self, process_id: str) -> None:
        await self._request("stop", process=process_id)

    async def restart(self, process_id: str, prefix: str | None = None,
                      log_level: str | None = None) -> None:
        """As Supervisor.restart: `prefix` runs it under a tool until a plain restart."""
        extra = {k: v for k, v in (("prefix", prefix), ("log_level", log_level))
                 if v is not None}
        await self._request("restart", process=process_id, **extra)

    async def shutdown(self, reason: str = "shutdown") -> None:
        self._stopping = True
        await self._request("shutdown", reason=reason)

    async def run_action(self, action_id: str) -> None:
        await self._request("run_action", action=action_id)

    async def replace_plan(self, plan: Plan) -> PlanDiff:
        """Relaunches with the session's accepted arguments (the plan was resolved from them);
        the server serialises relaunches and tells every client."""
        result = await self._request("apply", arguments=self.session.arguments)
        stop, start = list(result["stop"]), list(result["start"])
        return PlanDiff([], stop, start)

    async def detach(self) -> None:
        self.detached = True
        self._writer.close()

    def kill_all(self) -> None:
        """While a shutdown runs: SIGKILL what is left, now. Otherwise the UI is being torn
        down without a shutdown: a session it started in the foreground (and not told to
        outlive a hang-up) is stopped by its server; others run on."""
        if self._stopping:
            if not self._send_once({"id": 1, "op": "kill"}):
                self._kill_server()
        elif self.owner and not self.keep_on_hangup and not self.detached:
            self._send_once({"id": 1, "op": "shutdown", "reason": "the UI ended"})

    def _send_once(self, request: dict[str, Any]) -> bool:
        """A request from a thread without the engine loop (the UI's teardown); False when
        the server is there but does not answer (stopped or stuck)."""
        try:
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock:
                sock.settimeout(2.0)
                sock.connect(str(session_dir.socket_path(self.name)))
                sock.sendall(encode(request))
                sock.recv(4096)  # the hello: the request is read before we hang up
        except TimeoutError:
            return False
        except OSError:
            pass  # the server is gone, and with it what the request was about
        return True

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


class RemoteLifecycle:
    """The lifecycle states of the session's nodes, as its server's events report them, and
    the operator's transitions, asked of the server (which asks the node)."""

    def __init__(self, remote: RemoteSupervisor) -> None:
        self.remote = remote
        self.states: dict[str, str] = {}

    def follow(self, process: str, state: str) -> None:
        if state:
            self.states[process] = state
        else:
            self.states.pop(process, None)  # the node is gone

    async def request(self, process: str, transition: str) -> bool:
        result = await self.remote.request("transition", process=process,
                                            transition=transition)
        return bool(result.get("done"))


def _batched(events: list[Event]) -> list[Event]:
    """Consecutive output lines of one process and stream as one event."""
    out: list[Event] = []
    for event in events:
        last = out[-1] if out else None
        if (event.kind == "output" and last is not None and last.kind == "output"
                and last.process == event.process and last.stream == event.stream):
            last.lines.append(*event.lines)
        else:
            out.append(event)
    return out
