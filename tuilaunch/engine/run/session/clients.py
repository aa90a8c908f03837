"""The session server's clients: one connection each, one bounded queue per subscriber.

Each subscribed client has a bounded queue: past its limit, output lines are dropped for that
client only (with a count), and a client that stops reading state changes altogether is
disconnected, so a stalled or dead client never holds up the supervisor. What a request
does is the server's (`answer`); here is only how requests come in and replies and event
batches go out, never interleaved inside a line.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import itertools
import os
import re
import socket
import struct
from array import array
from collections.abc import Awaitable, Callable
from typing import Any

from ...errors import LaunchError
from ..event_buffer import EventBuffer
from ..events import Event, Output, View
from ..vocabulary.request import Request, UnknownRequest, from_message
from ..vocabulary.requests import ReadStamps, SetView, Subscribe
from ..vocabulary.text import strip_ansi
from .protocol import MESSAGE_TEXT, ProtocolError, Stamps, decode, encode, event_to_dict

CLIENT_MAX_LINES = 20_000
"""Output lines queued per client before the oldest are dropped for that client."""
CLIENT_MAX_EVENTS = 10_000
"""State events queued for a client that reads nothing; past this it is disconnected."""
KEPT_STAMPS = 50_000
"""The ROS stamps kept for a display not shown them: more lines than its panes hold."""


class ClientQueue:
    """One subscriber's bounded queue, drained by its own writer task."""

    def __init__(self, max_lines: int = CLIENT_MAX_LINES, interval: float = 0.0,
                 on_overflow: Callable[[], None] | None = None,
                 kinds: frozenset[str] | None = None, fair: bool = False,
                 only: str | None = None, plain: bool = False, stamps: bool = True) -> None:
        self.buffer = EventBuffer(max_lines=max_lines, fair=fair)
        self.kinds = kinds  # only these kinds of events (`tuilaunch echo` wants no output)
        self.only = only
        """The one process whose output this client shows (its focused pane), None for all:
        the others' lines stay in their log files until it asks (`view`)."""
        self.plain = plain  # a display that shows no colour codes is not sent them
        self.stamps = KeptStamps(stamps)
        self.sent_states: dict[str, str] = {}
        """The states this client was last told: a batch carries only the ones changed."""
        self.on_overflow = on_overflow
        self.interval = interval  # a display asks for no more batches than it draws
        self.events = 0
        self.ready = asyncio.Event()
        self.prompt = asyncio.Event()  # send now, without waiting for the interval
        self.overflowed = False

    def __call__(self, event: Event) -> None:
        if self.kinds is not None and event.kind not in self.kinds:
            return
        if self.only is not None and isinstance(event, Output) and event.process != self.only:
            return  # not on its screen: in the log file, read if it switches to it
        if not isinstance(event, Output):
            self.events += 1
            if self.events > CLIENT_MAX_EVENTS and not self.overflowed:
                self.overflowed = True
                if self.on_overflow is not None:
                    self.on_overflow()  # its writer may be stuck; cut it loose now
        self.buffer(event)
        self.ready.set()

    def take(self) -> list[Event]:
        self.ready.clear()
        self.events = 0
        return self.buffer.drain()


class KeptStamps:
    """A plain display's output lines, counted as sent, and the ROS stamps of the last
    KEPT_STAMPS of them: sent in the batches while `sending` (its time column or raw format
    shown), else kept here until it asks for them (op `stamps`). Over a link they are a
    sixth of a flood's batch, for a column a pane does not show until asked."""

    def __init__(self, sending: bool) -> None:
        self.sending = sending
        self.first = 0  # the line whose stamp is kept[0]
        self.kept = array("q")  # ms; -1 for a line without

    def add(self, stamps: list[int | None]) -> None:
        self.kept.extend(-1 if ms is None else ms for ms in stamps)
        if len(self.kept) > 2 * KEPT_STAMPS:  # trimmed now and then, not on every batch
            cut = len(self.kept) - KEPT_STAMPS
            del self.kept[:cut]
            self.first += cut

    def since(self, line: int) -> dict[str, Any]:
        """The `stamps` op's answer: the kept stamps from `line` on."""
        first = max(line, self.first)
        kept = self.kept[first - self.first:]
        return {"first": first,
                "stamps": Stamps().encode([None if ms < 0 else ms for ms in kept])}


class ClientHub:
    """Every connection of a session server: reads requests, answers them, pumps events.

    `hello()`: what a client is told on connecting; `snapshot()`: what a subscriber gets
    with its subscription (states and log sizes at that instant); `answer(request,
    client)`: the result of one request, decoded (vocabulary/request.py), from that client
    (raising LaunchError/TypeError/ValueError for a refusal);
    `states()`: the processes' states sent along with each batch; `gone(client)`: a client
    has disconnected (its keyboard, resource watch and plugins' streams are let go)."""

    def __init__(self, hello: Callable[[], dict[str, Any]],
                 snapshot: Callable[[], dict[str, Any]],
                 answer: Callable[[Request[Any], int], Awaitable[Any]],
                 states: Callable[[], dict[str, str]],
                 gone: Callable[[int], None],
                 offsets: Callable[[], dict[str, int]] | None = None) -> None:
        self.hello = hello
        self.snapshot = snapshot
        self.answer = answer
        self.states = states
        self.gone = gone
        self.offsets = offsets or (lambda: {})  # each log file's size, now
        self.ids = itertools.count(1)
        self.clients: dict[int, ClientQueue] = {}  # subscribed clients' queues, by client id
        self.queues: set[ClientQueue] = set()
        self.writers: set[asyncio.StreamWriter] = set()
        self.tasks: set[asyncio.Task[Any]] = set()
        self.connections: set[asyncio.Task[Any]] = set()
        """The tasks serving each connection (`serve`), awaited at the end: one still
        running when the loop closes is cancelled, and Python 3.11's stream server then
        logs that cancellation as a traceback ("Exception in callback
        StreamReaderProtocol.connection_made...")."""
        self.dropped_clients = 0
        self.ended = False  # the supervisor's run is over; writers send "ended" and stop
        self.status_code = 0

    def broadcast(self, event: Event) -> None:
        for queue in list(self.queues):
            queue(event)

    def send(self, event: Event, client: int) -> None:
        addressed = self.clients.get(client)
        if addressed is not None and addressed in self.queues:
            addressed(event)

    def subscribed(self, client: int) -> bool:
        queue = self.clients.get(client)
        return queue is not None and queue in self.queues

    def spawn(self, coroutine: Any) -> asyncio.Task[Any]:
        """A task the end waits for (a little) before closing the connections."""
        task = asyncio.ensure_future(coroutine)
        self.tasks.add(task)
        task.add_done_callback(self.tasks.discard)
        return task

    async def end(self, status: int) -> None:
        """The run is over: every subscriber gets what is left, then `ended`."""
        self.status_code = status
        self.ended = True
        for queue in list(self.queues):
            queue.ready.set()  # writers flush what is left, then send "ended"
        if self.tasks:  # a client that stopped reading must not keep the server alive
            await asyncio.wait([*self.tasks], timeout=5.0)
        for writer in list(self.writers):
            transport = writer.transport
            if transport.get_write_buffer_size() > transport.get_write_buffer_limits()[1]:
                # still full: a client that stopped reading, whose close would wait for it
                transport.abort()
            else:
                writer.close()
        # each connection now reads its end and returns: wait for that, so none is left
        # for the loop's close to cancel
        if self.connections:
            await asyncio.wait([*self.connections], timeout=5.0)

    async def serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        """One connection, from hello to its end (the unix server's client callback)."""
        sock = writer.get_extra_info("socket")
        if sock is not None and not same_user(sock):
            writer.close()
            return
        self.writers.add(writer)
        connection = asyncio.current_task()
        if connection is not None:
            self.connections.add(connection)
        lock = asyncio.Lock()
        queue: ClientQueue | None = None
        client = next(self.ids)
        try:
            await send_message(writer, lock, {"type": "hello", "info": self.hello()})
            while True:
                try:
                    line = await reader.readline()
                except (ValueError, ConnectionError):
                    return  # longer than MAX_MESSAGE, or the peer vanished
                if not line:
                    return
                message: dict[str, Any] = {}
                try:
                    message = decode(line)
                    request = from_message(message)
                except (ProtocolError, UnknownRequest) as exc:
                    await send_message(writer, lock, {"type": "reply", "id": message.get("id"),
                                                      "ok": False, "error": str(exc)})
                    continue
                if isinstance(request, Subscribe) and queue is None:
                    kinds = request.kinds
                    queue = ClientQueue(
                        max(1, min(request.max_lines or CLIENT_MAX_LINES, CLIENT_MAX_LINES)),
                        max(0.0, min(request.interval, 1.0)), writer.transport.abort,
                        None if kinds is None else frozenset(map(str, kinds)),
                        request.fair, request.only, request.plain, request.stamps)
                    # states and file sizes at the same instant as the subscription: the
                    # client reads the files up to these sizes, then gets events from here
                    result = self.snapshot()
                    queue.sent_states = dict(result.get("states") or {})
                    self.queues.add(queue)
                    self.clients[client] = queue
                    await send_message(writer, lock, {"type": "reply", "id": message.get("id"),
                                                      "ok": True, "result": result})
                    self.spawn(self._pump(queue, writer, lock))
                    continue
                if isinstance(request, ReadStamps) and queue is not None:
                    # answered here, between two batches: the batches before it are
                    # already written (the lock is first come, first served), and the
                    # ones after it carry their stamps when `on`
                    since = request.since
                    result = queue.stamps.since(since) if since is not None else \
                        {"first": 0, "stamps": []}
                    queue.stamps.sending = request.on
                    await send_message(writer, lock, {"type": "reply", "id": message.get("id"),
                                                      "ok": True, "result": result})
                    continue
                if isinstance(request, SetView) and queue is not None:
                    self._view(queue, request.only)
                    await send_message(writer, lock, {"type": "reply", "id": message.get("id"),
                                                      "ok": True, "result": {}})
                    continue
                # the client is the connection's: a client cannot speak for another
                self.spawn(self._answer(request, client, message.get("id"), writer, lock))
        except (ConnectionError, OSError):
            return
        finally:
            if queue is not None:
                self.queues.discard(queue)
                queue.ready.set()
            self.clients.pop(client, None)
            self.gone(client)
            self.writers.discard(writer)
            if connection is not None:
                self.connections.discard(connection)
            writer.close()

    def _view(self, queue: ClientQueue, only: str | None) -> None:
        """The client now shows `only`'s output (None: every process's). A `view` event in
        its stream marks the switch, with each log file's size at that instant: the lines
        before it that the client was not sent are in the files up to there, and the lines
        after it come as events."""
        queue.only = only
        queue.buffer(View(only, data={"offsets": self.offsets()}))
        queue.ready.set()
        queue.prompt.set()

    async def _pump(self, queue: ClientQueue, writer: asyncio.StreamWriter,
                    lock: asyncio.Lock) -> None:
        """Sends a client its queued events, one batch per round trip of the socket."""
        try:
            while queue in self.queues and not self.ended:
                await queue.ready.wait()
                if queue.overflowed:
                    self.dropped_clients += 1
                    break
                await self._send_events(queue, writer, lock)
                if queue.interval:
                    # a pane switched meanwhile (`view`) is not kept waiting the interval
                    with contextlib.suppress(TimeoutError):
                        await asyncio.wait_for(queue.prompt.wait(), queue.interval)
                    queue.prompt.clear()
            if self.ended:
                await self._send_events(queue, writer, lock)
                await send_message(writer, lock, {"type": "ended", "status": self.status_code})
        except (ConnectionError, OSError):
            pass
        finally:
            self.queues.discard(queue)
            writer.close()

    async def _send_events(self, queue: ClientQueue, writer: asyncio.StreamWriter,
                           lock: asyncio.Lock) -> None:
        events = queue.take()
        if not events:
            return
        # every state that changed since this client's last batch, not only those of the
        # events' processes: a relaunch that disables a node makes it "skipped" with an
        # event of the launch's, not of the node's
        touched = {process: state for process, state in self.states().items()
                   if queue.sent_states.get(process) != state}
        queue.sent_states.update(touched)  # a flood's batches do not repeat "running"
        for part in in_messages(events):
            batch: dict[str, Any] = {"type": "events",
                                     "events": [event_to_dict(e, queue.plain) for e in part]}
            if queue.plain:  # on what is sent, not on every line of a flood
                stamps = Stamps()
                for data in batch["events"]:
                    if data["kind"] == "output":
                        data["lines"] = [shown_line(line) for line in data.get("lines") or []]
                        queue.stamps.add(stamps.pack(data) if queue.stamps.sending
                                         else stamps.take(data))
            if touched:
                batch["states"] = touched
            await send_message(writer, lock, batch)

    async def _answer(self, request: Request[Any], client: int, request_id: Any,
                      writer: asyncio.StreamWriter, lock: asyncio.Lock) -> None:
        try:
            result = await self.answer(request, client)
            reply = {"type": "reply", "id": request_id, "ok": True, "result": result}
        except (LaunchError, TypeError, ValueError) as exc:
            reply = {"type": "reply", "id": request_id, "ok": False, "error": str(exc)}
        except Exception as exc:  # one bad request must never take the session down
            reply = {"type": "reply", "id": request_id, "ok": False,
                     "error": f"{request.op} failed: {type(exc).__name__}: {exc}"}
        try:
            await send_message(writer, lock, reply)
        except (ConnectionError, OSError):
            pass  # the asker is gone; what it asked for was done all the same


_ROS_STAMP = re.compile(r"^(\[[A-Z]+\]\s*\[\d+\.\d{3})\d+\]")


def in_messages(events: list[Event], budget: int = MESSAGE_TEXT) -> list[list[Event]]:
    """A batch as the messages that carry it, in order: one unless its lines hold more
    than `budget` characters (long lines, kept whole), when an output event's lines are
    spread over several."""
    parts: list[list[Event]] = [[]]
    size = 0
    for event in events:
        if not isinstance(event, Output):
            parts[-1].append(event)
            continue
        whole = sum(map(len, event.lines))  # a flood's lines are counted, not walked
        if size + whole <= budget:
            parts[-1].append(event)
            size += whole
            continue
        taken: list[str] = []
        for line in event.lines:
            if size + len(line) > budget and (size or taken):
                if taken:
                    parts[-1].append(dataclasses.replace(event, lines=taken))
                parts.append([])
                taken, size = [], 0
            taken.append(line)
            size += len(line)
        if taken or not event.lines:
            parts[-1].append(event if len(taken) == len(event.lines) else
                             dataclasses.replace(event, lines=taken))
    return [part for part in parts if part]


def shown_line(line: str) -> str:
    """A line as a display shows it: without colour codes, its ROS stamp to the
    millisecond (the pane's time column; the log file keeps the nanoseconds)."""
    if "\x1b" in line:
        line = strip_ansi(line)
    return _ROS_STAMP.sub(r"\1]", line, count=1) if line.startswith("[") else line


async def send_message(writer: asyncio.StreamWriter, lock: asyncio.Lock,
                       message: dict[str, Any]) -> None:
    async with lock:  # replies and event batches never interleave inside a line
        writer.write(encode(message))
        await writer.drain()


def same_user(sock: socket.socket) -> bool:
    """Whether the peer of a unix socket runs as this process's user (SO_PEERCRED)."""
    try:
        raw = sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i"))
    except (OSError, AttributeError):
        return False
    _, uid, _ = struct.unpack("3i", raw)
    return uid == os.getuid()
