"""The inspector's streams a client asked a session server for (rates, echo, plots, CPU
and memory, QoS marks), as the requests that asked: a stream ends with the connection that
carried it, so a client's new connection (a dropped ssh link, reconnected) asks again."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.request import Request
from ...engine.run.vocabulary.requests import (
    EchoStart,
    EchoStop,
    PlotStart,
    PlotStop,
    WatchQos,
    WatchRates,
    WatchResources,
)


class Watches:
    """The streams running for one client, kept as their requests."""

    def __init__(self) -> None:
        self.asked: dict[str, Request[Any]] = {}

    def note(self, request: Request[Any]) -> None:
        """A request that went through: a stream it starts is kept, one it ends dropped."""
        match request:
            case WatchRates(topics=topics):
                key, on = request.op, bool(topics)
            case EchoStart(topic=topic) | EchoStop(topic=topic):
                key, on = f"echo {topic}", isinstance(request, EchoStart)
            case PlotStart(topic=topic) | PlotStop(topic=topic):
                key, on = f"plot {topic}", isinstance(request, PlotStart)
            case WatchResources(on=on) | WatchQos(on=on):
                key = request.op
            case _:
                return
        if on:
            self.asked[key] = request
        else:
            self.asked.pop(key, None)

    async def ask_again(self, call: Callable[[Request[Any]], Awaitable[Any]],
                        warn: Callable[[str], None]) -> None:
        """On a new connection: each stream asked for again with `call(request)`; one the
        server refuses now (its topic went away meanwhile, say) is dropped, and said."""
        for key, asked in list(self.asked.items()):
            try:
                await call(asked)
            except SessionError as exc:
                self.asked.pop(key, None)
                warn(f"not watched again: {exc}")
