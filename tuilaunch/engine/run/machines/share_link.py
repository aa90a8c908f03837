"""One other machine's share of a placed launch as the launching side holds it: its session
there, the link to it, and what the coordinator (machines_share.py) keeps about it between
links (events seen, log offsets, lines asked for, requests waiting for it to be reached).
"""

from __future__ import annotations

import asyncio
import collections
import itertools
from typing import Any, TypeVar

from ...errors import LaunchError
from ...plan.machines import Machine
from ..process.logfiles import LogFile
from ..session.protocol import encode
from ..vocabulary.request import Request, to_message
from .remote import RemoteLink

REQUEST_IDS = itertools.count(1)
"""The ids of the launching side's requests to the shares (one count: a reply is matched
to its request by id alone)."""
R = TypeVar("R")

ASK_TIMEOUT = 30.0
"""How long a request waits for its share's reply (a restart there stops, then starts)."""


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
        self.typing: str | None = None
        """The process whose keyboard this side holds there (a new link holds none: the
        share gave it back when the last one closed)."""
        self.unknown: dict[str, str] = {}
        """The processes shown `unknown` since its link was lost, and the state each had."""

    def tell(self, outcome: str | None) -> None:
        """The outcome of an attempt to reach it, to the requests waiting for one."""
        waiters, self.waiters = self.waiters, []
        for waiter in waiters:
            if not waiter.done():
                waiter.set_result(outcome)

    async def send(self, request: Request[Any], request_id: int | None = None) -> None:
        """A request whose reply nobody waits for (None: none is sent back)."""
        if self.writer is None:
            raise LaunchError(f"{self.machine.name} is not connected")
        self.writer.write(encode(to_message(request, request_id)))
        await self.writer.drain()

    async def ask(self, request: Request[R], timeout: float = ASK_TIMEOUT) -> R:
        """A request of the session protocol to the share; its result (LaunchError with the
        share's words when it refuses, or when the link is lost before it answers)."""
        request_id = next(REQUEST_IDS)
        future: asyncio.Future[Any] = asyncio.get_running_loop().create_future()
        self.replies[request_id] = future
        try:
            await self.send(request, request_id)
            return request.reply(await asyncio.wait_for(future, timeout))
        except TimeoutError:
            raise LaunchError(f"{self.machine.name} did not answer within {timeout:g} s "
                              f"({request.op})") from None
        except (ConnectionError, OSError):
            raise LaunchError(f"lost the link to {self.machine.name}") from None
        finally:
            self.replies.pop(request_id, None)


__all__ = ["Share"]
