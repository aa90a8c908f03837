"""One other machine's share of a placed launch as the launching side holds it: its session
there, the link to it (a Connection over ssh, as every client's: session/connection.py),
the pace of its reconnection (a Reconnector), and what the coordinator (machines_share.py)
keeps about it between links (events seen, log offsets, lines asked for, requests waiting
for it to be reached).
"""

from __future__ import annotations

import asyncio
import collections
from typing import Any, TypeVar

from ...errors import LaunchError
from ...plan.machines import Machine
from ..process.logfiles import LogFile
from ..session.connection import Connection
from ..session.reconnector import Reconnector
from ..vocabulary.request import Request
from .remote import RemoteLink

R = TypeVar("R")

ASK_TIMEOUT = 30.0
"""How long a request waits for its share's reply (a restart there stops, then starts)."""
RECONNECT_FIRST = 1.0
"""Seconds before the first attempt to reach a share again after its link dropped."""
RECONNECT_MOST = 10.0
"""The longest wait between attempts (they double from the first)."""


class Share:
    """One other machine's share: its session there and the link to it."""

    def __init__(self, machine: Machine, session: str) -> None:
        self.machine = machine
        self.session = session
        self.conn: Connection | None = None
        """The link's connection while it is up (None while it is down)."""
        self.link: RemoteLink | None = None
        self.relink = Reconnector(RECONNECT_FIRST, RECONNECT_MOST)
        """The pace of the attempts to reach it again; `now` cuts the wait short."""
        self.ended = asyncio.Event()
        self.failure: str | None = None
        self.seen: set[tuple[Any, ...]] = set()  # events mirrored (a reconnect repeats them)
        self.logs: dict[str, LogFile] = {}
        self.offsets: dict[str, int] = {}  # its log files' sizes at the last subscription
        self.received: collections.Counter[str] = collections.Counter()
        """Lines of each process that came as events since the last subscription: they are
        in its log file there after `offsets`, and are skipped when the lines the link
        missed are asked for. A count, not a time: many lines share a millisecond."""
        self.backfill: set[str] = set()  # processes whose missed lines are still unanswered
        self.held: list[dict[str, Any]] = []  # events batches waiting for those lines
        self.following = False  # a task starts, follows or reconnects it now
        self.waiters: list[asyncio.Future[str | None]] = []
        """Requests waiting for the next attempt to reach it: told None once connected,
        else why not."""
        self.typing: str | None = None
        """The process whose keyboard this side holds there (a new link holds none: the
        share gave it back when the last one closed)."""
        self.unknown: dict[str, str] = {}
        """The processes shown `unknown` since its link was lost, and the state each had."""

    @property
    def address(self) -> str:
        """Its session as the user writes it (`tuilaunch stop HOST:NAME`)."""
        return f"{self.machine.host}:{self.session}"

    def tell(self, outcome: str | None) -> None:
        """The outcome of an attempt to reach it, to the requests waiting for one."""
        waiters, self.waiters = self.waiters, []
        for waiter in waiters:
            if not waiter.done():
                waiter.set_result(outcome)

    async def send(self, request: Request[Any], reply: bool = True) -> None:
        """A request whose reply nobody waits for (`reply` False: none is sent back)."""
        if self.conn is None:
            raise LaunchError(f"{self.machine.name} is not connected")
        self.conn.send(request, reply)
        await self.conn.writer.drain()

    async def ask(self, request: Request[R], timeout: float = ASK_TIMEOUT) -> R:
        """A request of the session protocol to the share; its result (SessionError with the
        share's words when it refuses, LaunchError when the link is lost before it
        answers). The coordinator's reading of the link matches the reply."""
        if self.conn is None:
            raise LaunchError(f"{self.machine.name} is not connected")
        try:
            return await asyncio.wait_for(self.conn.ask(request), timeout)
        except TimeoutError:
            raise LaunchError(f"{self.machine.name} did not answer within {timeout:g} s "
                              f"({request.op})") from None
        except (ConnectionError, OSError):
            raise LaunchError(f"lost the link to {self.machine.name}") from None


__all__ = ["ASK_TIMEOUT", "Share"]
