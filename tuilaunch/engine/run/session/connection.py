"""One connection to a session server, asyncio: greeted once (protocol.greet), requests
numbered, replies matched to them by id, the other messages handed to whoever follows it.

Every client speaks through it (the TUI's and the fleet's RemoteSupervisor, plots,
`attach`), over a session's unix socket or an ssh link's socket alike; the CLI's one-shot
commands too, through client/link.py's Link, a blocking face that runs one Connection on an
event loop of its own. A lost link is reconnected by a new Connection, paced by a
Reconnector (reconnector.py).

Two ways to be answered, as a client needs: `ask` waits for its reply while another task
`receive`s the stream (the reply is matched there); `call` reads the stream itself until
its reply (opening, reconnecting, a step that must happen before the next message is
handled, every request of a one-shot command), keeping what came meanwhile for `receive`
and `next_message`, in order.
"""

from __future__ import annotations

import asyncio
import collections
import concurrent.futures
import contextlib
import time
from collections.abc import Callable, Coroutine
from typing import Any, TypeVar

from ..vocabulary.request import Request, to_message
from .protocol import MAX_MESSAGE, ProtocolError, decode, encode, greet
from .session_dir import SessionError

R = TypeVar("R")


def run_blocking(work: Callable[[], Coroutine[Any, Any, R]]) -> R:
    """`work` run to its end on a loop of its own, for a blocking caller: in this thread,
    or in one of its own when this thread runs a loop already."""
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return asyncio.run(work())
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        return pool.submit(lambda: asyncio.run(work())).result()


def reply_result(message: dict[str, Any], label: str) -> Any:
    """A reply's result; SessionError naming the session (NAME or HOST:NAME) with the
    server's words when it refused."""
    if not message.get("ok"):
        raise SessionError(f"session {label}: {message.get('error')}")
    return message.get("result")


class NoGreeting(SessionError):
    """The server's first line was no greeting: `garbled` says what it was instead (not
    JSON: no tuilaunch speaks there), None when the stream closed before a whole line (what
    carries the link failed: an ssh link's own words say why)."""

    def __init__(self, message: str, garbled: str | None) -> None:
        super().__init__(message)
        self.garbled = garbled


class Connection:
    """A greeted connection: `info` is the hello's; `label` names the session in errors."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                 info: dict[str, Any], label: str) -> None:
        self.reader = reader
        self.writer = writer
        self.info = info
        self.label = label
        self.last_heard = time.monotonic()
        """When the other side last sent anything (a link's silence is shown from it)."""
        self.ended = False
        """The session said it ended (its last message), read here or by `call`."""
        self._next_id = 0
        self._replies: dict[int, asyncio.Future[dict[str, Any]]] = {}
        self.early: collections.deque[dict[str, Any]] = collections.deque()
        """What `call` read before its reply, in order: the next messages `receive` and
        `next_message` give."""

    @classmethod
    async def greeted(cls, reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                      label: str, timeout: float | None = None) -> Connection:
        """Reads the server's greeting (at most `timeout` s: TimeoutError) and checks it:
        VersionMismatch, NoGreeting or SessionError in one line, the writer then closed.
        The one place a client checks a greeting (ssh links too: remote.py)."""
        try:
            try:
                line = await asyncio.wait_for(reader.readline(), timeout)
            except (ConnectionError, ValueError) as exc:  # reset; a line past MAX_MESSAGE
                raise NoGreeting(f"session {label} did not greet ({exc})", None) from None
            if not line.endswith(b"\n"):  # closed before a whole line
                raise NoGreeting(f"session {label} did not greet", None)
            try:
                return cls(reader, writer, greet(line, label), label)
            except ProtocolError as exc:  # not a tuilaunch
                raise NoGreeting(f"session {label} did not greet ({exc})", str(exc)) from None
        except BaseException:
            writer.close()
            raise

    @classmethod
    async def open_unix(cls, path: str, label: str, timeout: float,
                        hint: str | None = None) -> Connection:
        """A session's socket on this machine, connected and greeted within `timeout` s
        each (a stopped server's full backlog holds the connect); `hint`: what the error of
        a socket nobody listens on adds."""
        try:
            async with asyncio.timeout(timeout):
                reader, writer = await asyncio.open_unix_connection(path, limit=MAX_MESSAGE)
        except TimeoutError:  # an OSError too, but the caller's to say: not answering
            raise
        except OSError as exc:
            raise SessionError(f"session {label} does not answer ({exc.strerror or exc})",
                               hint=hint) from None
        return await cls.greeted(reader, writer, label, timeout)

    @classmethod
    async def on_socket(cls, sock: Any, info: dict[str, Any], label: str) -> Connection:
        """One over a socket already greeted (an ssh link, whose greeting is read when it is
        made: remote.open_remote_link)."""
        sock.setblocking(False)
        reader, writer = await asyncio.open_connection(sock=sock, limit=MAX_MESSAGE)
        return cls(reader, writer, info, label)

    # --- asking -------------------------------------------------------------------------------

    def send(self, request: Request[Any], reply: bool = True) -> int:
        """Writes `request` (numbered, unless `reply` is False: no reply then comes) without
        waiting; its id. A reply nobody waits for is passed over."""
        self._next_id += 1
        self.writer.write(encode(to_message(request, self._next_id if reply else None)))
        return self._next_id

    async def ask(self, request: Request[R]) -> R:
        """The reply to `request`, matched by `receive` in another task (replies may come
        in any order); SessionError with the server's words, or `fail`'s."""
        request_id = self.send(request)
        future: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self._replies[request_id] = future
        try:
            await self.writer.drain()
            return request.reply(reply_result(await future, self.label))
        finally:
            self._replies.pop(request_id, None)

    async def call(self, request: Request[R], idle: float | None = None) -> R:
        """The reply to `request`, read here: for a step taken while nobody `receive`s.
        ConnectionError when the stream closes first; TimeoutError when nothing at all came
        for `idle` s (a session streaming events meanwhile is answering)."""
        request_id = self.send(request)
        await self.writer.drain()
        while True:
            line = await self._line(idle)
            if not line:
                raise ConnectionError(f"the link closed during {request.op}")
            message = self._heard(decode(line))
            if message.get("type") == "reply" and message.get("id") == request_id:
                return request.reply(reply_result(message, self.label))
            self.early.append(message)

    async def _line(self, idle: float | None) -> bytes:
        if idle is None:  # the TUI's stream: no timer per line
            line = await self.reader.readline()
        else:
            async with asyncio.timeout(idle):
                line = await self.reader.readline()
        if line:
            self.last_heard = time.monotonic()
        return line

    def _heard(self, message: dict[str, Any]) -> dict[str, Any]:
        if message.get("type") == "ended":
            self.ended = True
        return message

    # --- following ----------------------------------------------------------------------------

    async def receive(self) -> dict[str, Any] | None:
        """The next message that is not a reply (events, ended), what `call` kept first;
        replies go to their `ask`. None once the stream closed."""
        while True:
            message = await self.next_message()
            if message is None or message.get("type") != "reply":
                return message
            future = self._replies.pop(message.get("id", -1), None)
            if future is not None and not future.done():
                future.set_result(message)

    async def next_message(self, idle: float | None = None) -> dict[str, Any] | None:
        """The next message whatever it is, replies too (a request `send` without waiting
        is answered among the events), what `call` kept first; None once the stream closed,
        TimeoutError after `idle` s of silence (the connection stays usable)."""
        while not self.early:
            try:
                line = await self._line(idle)
            except (ConnectionError, ValueError):  # ValueError: past MAX_MESSAGE
                line = b""
            if not line:
                return None
            with contextlib.suppress(ProtocolError):
                return self._heard(decode(line))
        return self.early.popleft()

    def forget_early(self) -> None:
        """Drops what `call` kept: a reconnection that failed midway reads it again."""
        self.early.clear()

    def fail(self, why: str) -> None:
        """Every `ask` waiting is told `why` (the stream is gone)."""
        for future in self._replies.values():
            if not future.done():
                future.set_exception(SessionError(why))
        self._replies.clear()

    @property
    def closing(self) -> bool:
        return self.writer.is_closing()

    def close(self) -> None:
        with contextlib.suppress(RuntimeError):  # its loop already closed
            self.writer.close()
