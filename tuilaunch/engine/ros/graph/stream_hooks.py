"""What the inspector's per-client streams (echo, plot, hz, rates) take from it: the
launch's bridge, why a topic cannot be read, and the way to a client."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Awaitable, Callable, Coroutine
from dataclasses import dataclass
from typing import Any

from ...errors import LaunchError
from ...run.events import Event


@dataclass(frozen=True)
class StreamHooks:
    bridge: Callable[[], Awaitable[Any]]
    """The launch's bridge, made at the first request that needs it."""
    problem: Callable[[Any, str], Awaitable[str]]
    """`problem(bridge, topic)`: why a topic has no publisher to read."""
    subscribed: Callable[[int], bool]
    """Whether a client takes events: a stream sends nothing otherwise."""
    send: Callable[[Event, int], None]
    """An event to one client."""
    publisher_wait: float
    """The longest wait for a topic's first publisher."""

    async def no_publisher(self, bridge: Any, topic: str, wait: float) -> LaunchError:
        """The error of a stream whose topic had no publisher within `wait` s."""
        return LaunchError(f"{await self.problem(bridge, topic)} (waited {wait:g} s)")


async def stopped(*tasks: asyncio.Task[Any] | None) -> None:
    """Cancels the tasks and waits for their end: what one raises on its way out ends it
    too, and a closing inspector has no one to tell."""
    for task in tasks:
        if task is not None:
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task


def in_background(pending: set[asyncio.Task[Any]], work: Coroutine[Any, Any, Any]) -> None:
    """Runs `work` as a task kept in `pending` until done: a bare task may be collected."""
    task = asyncio.ensure_future(work)
    pending.add(task)
    task.add_done_callback(pending.discard)
