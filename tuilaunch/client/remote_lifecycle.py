"""The lifecycle side of a RemoteSupervisor (the TUI uses it as a Supervisor's)."""

from __future__ import annotations

from collections.abc import Awaitable, Callable

from ..engine.run.vocabulary.requests import Transition


class RemoteLifecycle:
    """The lifecycle states of the session's nodes, as its server's events report them, and
    the operator's transitions, asked of the server (which asks the node) with `request`,
    the supervisor's."""

    def __init__(self, request: Callable[[Transition], Awaitable[bool]]) -> None:
        self.request_server = request
        self.states: dict[str, str] = {}

    def follow(self, process: str, state: str) -> None:
        if state:
            self.states[process] = state
        else:
            self.states.pop(process, None)  # the node is gone

    async def request(self, process: str, transition: str) -> bool:
        return await self.request_server(Transition(process, transition))
