"""Typing into a node through a session: one client holds the keyboard at a time.

Two people typing into one gdb at once would interleave their keys; so a client asks for the
keyboard (`typing {process, on: true}`), sends keys (`input {process, data}`), and gives it
back (`on: false`, or by disconnecting). Every client is told who holds it by an event of
kind `typing` (`process`, `data: {"client": id or None}`), so the others can show it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...errors import LaunchError
from ..events import LIVE_STATES, Typing
from ..plugins import Handlers
from ..supervisor.supervisor import Supervisor
from ..vocabulary.requests import Input, TakeKeys


@dataclass
class Keyboard:
    """Who types into which process of one session's supervisor."""

    supervisor: Supervisor
    find: Any
    """Turns a client's process reference into a process id (or raises)."""
    client: int | None = None
    """The client holding the keyboard, if any."""
    process: str | None = None
    """The process it types into."""

    def handlers(self) -> Handlers:
        return {TakeKeys: self.typing, Input: self.input}

    def state(self) -> dict[str, Any] | None:
        """For `status`: who types into what, or None."""
        if self.client is None:
            return None
        return {"client": self.client, "process": self.process}

    async def typing(self, request: TakeKeys, client: int) -> dict[str, Any]:
        process = self.find(request.process)
        if not request.on:
            if self.client == client:
                self.release(client)
            return {}
        if self.client is not None and self.client != client:
            raise LaunchError(f"another client (client {self.client}) is typing into "
                              f"{self.process}; one client types at a time")
        state = self.supervisor.states.get(process)
        if state not in LIVE_STATES:  # a stop's prompt can still be answered
            raise LaunchError(f"{process} is not running ({state}): there is nothing to "
                              "type into")
        # a terminal here, or its keyboard on the machine that runs it taken for us
        await self.supervisor.take_keys(process)
        previous = self.process
        self.client, self.process = client, process
        if previous is not None and previous != process:
            self.supervisor.give_keys(previous)
            self._tell(previous, None)
        self._tell(process, self.client)
        return {}

    async def input(self, request: Input, client: int) -> dict[str, Any]:
        process, data = self.find(request.process), request.data
        if self.client != client or self.process != process:
            who = f"client {self.client} types into {self.process}" \
                if self.client is not None else "nobody holds the keyboard"
            raise LaunchError(f"input to {process} refused: {who}; ask for it with "
                              "typing {on: true} first")
        dropped = await self.supervisor.type_keys(process, data.encode())
        return {"dropped": dropped} if dropped else {}

    def release(self, client: int) -> None:
        """The client gives the keyboard back, or is gone."""
        if self.client != client:
            return
        process = self.process
        self.client = self.process = None
        if process is not None:
            self.supervisor.give_keys(process)
            self._tell(process, None)

    def _tell(self, process: str, client: int | None) -> None:
        self.supervisor.emit(Typing(process, data={"client": client}))
