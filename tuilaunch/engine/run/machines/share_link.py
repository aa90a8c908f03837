"""One other machine's share of a placed launch as the launching side holds it: its session
there, the link to it, and what the coordinator (machines_share.py) keeps about it between
links (events seen, log offsets, lines asked for, requests waiting for it to be reached).
"""

from __future__ import annotations

import asyncio
import collections
from typing import Any

from ...errors import LaunchError
from ...plan.machines import Machine
from ..process.logfiles import LogFile
from ..session.protocol import encode
from .remote import RemoteLink


class Share:
    """One other machine's share: its session there and the link to it."""

    def __init__(self, machine: Machine, session: str) -> None:
        self.machine = machine
        self.session = session
        self.writer: asyncio.StreamWriter | None = None
        self.reader: asyncio.StreamReader | None = None
        self.link: RemoteLink | None = None
        self.ended = asyncio.Event()
        self.failure: str | None = None
        self.replies: dict[int, asyncio.Future[Any]] = {}
        self.seen: set[tuple[Any, ...]] = set()  # events mirrored (a reconnect repeats them)
        self.logs: dict[str, LogFile] = {}
        self.offsets: dict[str, int] = {}  # its log files' sizes at the last subscription
        self.received: collections.Counter[str] = collections.Counter()
        """Lines of each process that came as events since the last subscription: they are
        in its log file there after `offsets`, and are skipped when the lines the link
        missed are asked for. A count, not a time: many lines share a millisecond."""
        self.backfill: dict[int, str] = {}  # requests for lines still unanswered
        self.held: list[dict[str, Any]] = []  # events batches waiting for those lines
        self.following = False  # a task starts, follows or reconnects it now
        self.wake = asyncio.Event()  # cuts short the wait before the next attempt
        self.waiters: list[asyncio.Future[str | None]] = []
        """Requests waiting for the next attempt to reach it: told None once connected,
        else why not."""

    def tell(self, outcome: str | None) -> None:
        """The outcome of an attempt to reach it, to the requests waiting for one."""
        waiters, self.waiters = self.waiters, []
        for waiter in waiters:
            if not waiter.done():
                waiter.set_result(outcome)

    async def send(self, message: dict[str, Any]) -> None:
        if self.writer is None:
            raise LaunchError(f"{self.machine.name} is not connected")
        self.writer.write(encode(message))
        await self.writer.drain()


__all__ = ["Share"]
