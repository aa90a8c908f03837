"""A blocking connection to a session server, for the one-shot commands; finding a session
by name; what to say of a server that does not answer."""

from __future__ import annotations

import asyncio
import collections
import concurrent.futures
import contextlib
import socket
import threading
import time
from collections.abc import Callable, Coroutine, Iterator
from pathlib import Path
from typing import Any, TypeVar

from ..engine.run.machines.proxy import SERVER_GONE_WORDS
from ..engine.run.machines.remote import Address, open_remote_link, parse_address
from ..engine.run.session import session_dir
from ..engine.run.session.connection import Connection, run_blocking
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary.forward import Forward
from ..engine.run.vocabulary.request import Request

R = TypeVar("R")
T = TypeVar("T")


def resolve_name(name: str | None) -> str:
    """The named session, or the only one running."""
    alive = session_dir.live_sessions()
    if name is not None:
        session_dir.check_name(name)
        if name not in alive:
            raise SessionError(f"no running session named {name}",
                               hint=f"running: {', '.join(alive)}" if alive else
                               "tuilaunch ls lists the running sessions")
        return name
    if not alive:
        raise SessionError("no running session", hint="start one with tuilaunch FILE --detach")
    if len(alive) > 1:
        raise SessionError(f"several sessions run: {', '.join(alive)}", hint="name one")
    return alive[0]


ANSWER_TIMEOUT = 10.0
"""How long a client waits for the server's greeting and for a short reply: a server busy
starting a hundred processes answers in well under a second; one that is stopped (a stray
Ctrl+Z, `kill -STOP`) or stuck never does, and no command may hang on it."""


def not_answering(name: str, waited: float) -> SessionError:
    """What to say of a server that accepted the connection and then said nothing."""
    pid = (session_dir.read_info(name) or {}).get("pid")
    where = f"its server (pid {pid})" if pid else "its server"
    stopped = False
    try:
        stopped = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] in "Tt"
    except (OSError, IndexError, TypeError):
        pass
    state = "is stopped" if stopped else "is stopped or stuck"
    hint = (f"kill -CONT {pid} lets it go on; kill -9 {pid} ends it and its watchdog stops "
            "every node" if pid else "tuilaunch ls lists the sessions")
    return SessionError(f"session {name} did not answer within {waited:g} s: {where} {state}",
                        hint=hint)


class LinkLost(SessionError):
    """The ssh link to a session on another machine closed before the session said it
    ended: the session may well run on there. The streaming commands exit 1 with it (an
    ended session is another status): docs/command-line.md."""


LINK_LOST_STATUS = 1


def short_reason(reason: str, room: int) -> str:
    """A lost link's reason in `room` columns, its end kept: ssh says what failed last
    (`cannot reach robot1: connect to host 10.0.0.7 port 22: Connection refused`), and at
    80 columns `cannot reach robot1: … Connection refused` says more than its first half."""
    if len(reason) <= room:
        return reason
    head, _, rest = reason.partition(": ")
    last = rest.rsplit(": ", 1)[-1] if rest else reason
    short = f"{head}: … {last}" if rest and last != rest else reason
    if len(short) <= room:
        return short
    tail = f"… {last}"
    return tail if len(tail) <= room else "…" + last[len(last) - max(room - 1, 0):]


ATTEMPT_SHOWN = 1.0
"""Seconds an attempt to reconnect runs before the line says it: one refused at once (a
machine off the network) does not flash the line at every try."""


def relink_words(attempt: int, trying_for: float | None) -> str:
    """Where a lost link's reconnection is: `reconnecting` between tries, `retrying
    (attempt 2, 12 s)` while one is under way (ssh takes up to 15 s to notice a host that
    is gone, and a greeting up to 30: a reason older than that is not the news)."""
    if trying_for is None or trying_for < ATTEMPT_SHOWN:
        return "reconnecting"
    return f"retrying (attempt {attempt}, {trying_for:.0f} s)"


def lost_link_line(host: str, name: str, reason: str, attempt: int,
                   trying_for: float | None, room: int) -> str:
    """A TUI's lost-link line in `room` columns, its reason's end kept (`short_reason`):
    between tries `link to HOST lost · reconnecting · NAME · R: now · REASON`, during one
    `link to HOST lost · retrying (attempt 2, 12 s) · NAME · last: REASON` (R does nothing
    then; the name goes where 80 columns would cut the reason)."""
    if trying_for is None or trying_for < ATTEMPT_SHOWN:
        said = f"link to {host} lost · reconnecting · {name} · R: now · "
    else:
        said = f"link to {host} lost · {relink_words(attempt, trying_for)} · "
        named = f"{said}{name} · last: "
        said = named if room - len(named) >= len("… Connection refused") else said + "last: "
    return said + short_reason(reason, room - len(said))


class Link:
    """A blocking connection for one-shot commands (status, stop, restart, wait, logs): a
    synchronous face over one Connection (engine/run/session/connection.py: the greeting,
    the requests' numbers, the replies matched), which runs on an event loop of the link's
    own, in the calling thread, for each call.

    Connecting, the greeting and `request(..., short=True)` replies wait at most
    `answer_timeout`; `timeout` is what reading each message waits afterwards (None: as long
    as the session runs, for `stop`, `logs -f` and `wait`), changed between reads at will.
    A read that times out (TimeoutError) or is interrupted (Ctrl+C) leaves the link usable:
    `hz` asks for its last figures after either."""

    def __init__(self, name: str, timeout: float | None = ANSWER_TIMEOUT,
                 answer_timeout: float = ANSWER_TIMEOUT) -> None:
        self._start(name, None, timeout, answer_timeout)
        path = str(session_dir.socket_path(name))
        try:
            # a server of another protocol version says so here, before any request
            self.connection = self._run(Connection.open_unix(
                path, name, answer_timeout, hint="tuilaunch ls lists the running sessions"))
        except TimeoutError:
            self._end()
            raise not_answering(name, answer_timeout) from None
        except BaseException:
            self._end()
            raise

    @classmethod
    def connected(cls, name: str, sock: socket.socket, hello: dict[str, Any], host: str,
                  timeout: float | None = ANSWER_TIMEOUT,
                  answer_timeout: float = ANSWER_TIMEOUT,
                  on_close: Callable[[], None] | None = None,
                  why_lost: Callable[[], str] | None = None) -> Link:
        """A Link on a socket already connected and greeted: the ssh link to `host`'s
        session (engine/run/machines/remote.py). `on_close` ends what carries it (ssh);
        `why_lost` says why it closed (ssh's last words). The link reads a copy of `sock`:
        `release` leaves `sock` itself open (`attach` hands it to the TUI)."""
        self = cls.__new__(cls)
        self._start(name, host, timeout, answer_timeout)
        self._on_close, self._why_lost, self._given = on_close, why_lost, sock
        try:
            self.connection = self._run(Connection.on_socket(sock.dup(), hello["info"],
                                                             self.label))
        except BaseException:
            self._end()
            raise
        return self

    def _start(self, name: str, host: str | None, timeout: float | None,
               answer_timeout: float) -> None:
        self.name, self.host = name, host
        self.timeout, self.answer_timeout = timeout, answer_timeout
        self._on_close: Callable[[], None] | None = None
        self._why_lost: Callable[[], str] | None = None
        self._given: socket.socket | None = None
        self._loop = asyncio.new_event_loop()
        # one thread at a time runs the loop; `close` may come from another (plot --csv
        # reads each session in a thread and closes the links from the main one)
        self._turn = threading.Lock()
        self._closing = False

    info = Forward[dict[str, Any]](
        "connection", doc="What the session said of itself in its hello (name, pid, log_dir...).")
    ended = Forward[bool]("connection", doc="The session said it ended (its last message).")
    pending = Forward[collections.deque[dict[str, Any]]](
        "connection", "early", "The messages that came before a reply, in order: the next "
        "`receive` gives them.")

    # --- running the connection's coroutines ------------------------------------------------

    def _run(self, coro: Coroutine[Any, Any, T]) -> T:
        return self._blocking(lambda: self._run_here(coro))

    @staticmethod
    def _blocking(work: Callable[[], T]) -> T:
        """`work` here; in a thread of its own when this thread runs an event loop already
        (a coroutine that calls a command waits for it, as on a blocking socket)."""
        try:
            asyncio.get_running_loop()
        except RuntimeError:
            return work()
        with concurrent.futures.ThreadPoolExecutor(1) as pool:
            return pool.submit(work).result()

    def _run_here(self, coro: Coroutine[Any, Any, T]) -> T:
        with self._turn:
            if self._closing or self._loop.is_closed():  # closed by another thread
                coro.close()
                self._shut()
                raise ConnectionResetError("the link is closed")
            task = self._loop.create_task(coro)
            try:
                return self._loop.run_until_complete(task)
            except BaseException:
                # Ctrl+C (in the loop's wait, or in the task: then retrieved, never logged):
                # the read is given up and the link stays usable
                if not task.done():
                    task.cancel()
                    with contextlib.suppress(BaseException):
                        self._loop.run_until_complete(task)
                elif not task.cancelled():
                    task.exception()
                raise
            finally:
                if self._closing:
                    self._shut()

    def _shut(self) -> None:
        """The connection closed and its socket with it, then the loop (under `_turn`)."""
        if self._loop.is_closed():
            return
        connection: Connection | None = getattr(self, "connection", None)
        if connection is not None:
            connection.close()
        # the transport closes its socket on the loop's next turn
        with contextlib.suppress(BaseException):
            self._loop.run_until_complete(asyncio.sleep(0))
        self._loop.close()

    def _end(self) -> None:
        """Closes the connection and the loop, or has the thread reading close them."""
        self._closing = True
        if self._turn.acquire(blocking=False):
            try:
                self._blocking(self._shut)
            finally:
                self._turn.release()
        else:  # another thread is in a read: it ends with the stream, and closes the loop
            with contextlib.suppress(RuntimeError):  # that thread closed it meanwhile
                self._loop.call_soon_threadsafe(self.connection.close)

    # --- reading and asking -----------------------------------------------------------------

    def receive(self) -> dict[str, Any] | None:
        """The next message (what came before a reply first), waiting `timeout` at most
        (then TimeoutError); None when the server closed the connection."""
        return self._next(self.timeout)

    def _next(self, idle: float | None) -> dict[str, Any] | None:
        try:
            return self._run(self.connection.next_message(idle))
        except ConnectionError:  # closed by `close` from another thread
            return None

    def lost(self) -> SessionError | None:
        """Once the connection closed: LinkLost when it was the ssh link to a session that
        had not said it ended (the session may run on there); a SessionError when the
        proxy there saw its server die; None when the session ended (or is on this
        machine, where no link is between)."""
        if self.host is None or self.ended:
            return None
        reason = "closed"
        if self._why_lost is not None:
            try:
                reason = self._why_lost()
            except OSError:
                pass
        if SERVER_GONE_WORDS in reason:  # the link was up; the session is what ended
            return SessionError(f"{self.host}: {reason.split('error: ', 1)[-1]}")
        return LinkLost(f"link to {self.host} lost: {reason}")

    def send(self, request: Request[Any]) -> int:
        """Asks without waiting for the reply (it comes among the messages, with this id):
        `stop` reads the stopping's events while the server works on the shutdown."""
        request_id = self.connection.send(request)
        try:
            self._run(self.connection.writer.drain())
        except ConnectionError:
            raise self.lost() or SessionError(
                f"session {self.label} closed the connection during {request.op}") from None
        return request_id

    def receive_until(self, deadline: float | None) -> dict[str, Any] | None:
        """The next message (events that came with a reply first), waiting until
        `deadline` (time.monotonic) at most, then TimeoutError; the link can be read and
        asked again after it: `hz --duration` asks for the final figures, `echo --timeout`
        says what came."""
        if deadline is None:
            return self._next(self.timeout)
        return self._next(max(deadline - time.monotonic(), 0.0))

    def request(self, request: Request[R], short: bool = False) -> R:
        """The reply to `request`, as it reads it; `short`: an answer the server gives at
        once (status, find), so waiting longer than `answer_timeout` means it is not
        answering."""
        idle = self.answer_timeout if short else self.timeout
        try:
            return self._run(self.connection.call(request, idle))
        except TimeoutError:
            raise not_answering(self.name, idle or 0.0) from None
        except ConnectionError:
            raise self.lost() or SessionError(
                f"session {self.label} closed the connection during {request.op}") from None

    def messages(self) -> Iterator[dict[str, Any]]:
        """Messages as they come (after `subscribe`), until the server closes."""
        while True:
            message = self.receive()
            if message is None:
                lost = self.lost()
                if lost is not None:
                    raise lost  # not the session's end: never read as one
                return
            yield message

    def wait_closed(self) -> None:
        for _ in self.messages():
            pass

    def release(self) -> None:
        """Done with the link: the socket given to `connected` stays open for another
        client of the same link (nothing unasked is sent before a subscribe, so none is
        lost)."""
        self._end()
        if self._given is not None:  # blocking again, as it was given: the copy's mode
            self._given.settimeout(self._given.gettimeout())  # is the same file's

    def close(self) -> None:
        self._end()
        if self._on_close is not None:
            self._on_close()

    @property
    def label(self) -> str:
        """The session's address as the user writes it: NAME, or HOST:NAME."""
        return self.name if self.host is None else f"{self.host}:{self.name}"


LOCAL = "local"
"""The host name that means this computer (`local:NAME`, `ls local`, `stop local:`), as
the fleet's TUI labels its sessions."""


def parse_session(text: str) -> Address:
    """`[HOST:]NAME` as parse_address reads it, with `local:NAME` meaning NAME here."""
    where = parse_address(text)
    return Address(None, where.name) if where.host == LOCAL else where


def open_link(address: str | None, timeout: float | None = ANSWER_TIMEOUT,
              answer_timeout: float = ANSWER_TIMEOUT) -> Link:
    """A Link to `[HOST:]NAME` (None: the only session here); over ssh for a HOST."""
    if address is None:
        return Link(resolve_name(None), timeout, answer_timeout)
    where = parse_session(address)
    if where.host is None:
        return Link(resolve_name(where.name), timeout, answer_timeout)
    remote = open_remote_link(where.host, where.name)
    return Link.connected(where.name, remote.sock, remote.hello, where.host, timeout,
                          answer_timeout, on_close=remote.close, why_lost=remote.why_lost)


def send_once(name: str, request: Request[Any]) -> bool:
    """A request to a session on this machine from the UI's teardown (a thread without an
    event loop, or one whose loop is ending): sent once the server greets, and the
    connection closed; False when the server is there but does not answer (stopped or
    stuck)."""
    async def once() -> None:
        conn = await Connection.open_unix(str(session_dir.socket_path(name)), name, 2.0)
        try:
            conn.send(request, reply=False)
            await conn.writer.drain()
        finally:
            conn.close()

    try:
        run_blocking(once)
    except TimeoutError:
        return False
    except (SessionError, OSError):
        pass  # the server is gone, and with it what the request was about
    return True
