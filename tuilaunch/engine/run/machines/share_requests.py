"""What the launching side of a placed launch asks of the shares besides a start or a
stop: what their processes were started with (for its `status`), and their keyboards.

A process placed on another machine was started there, perhaps under a tool or with a
terminal a restart gave it: that machine's share says how, and the launching side's
`status` reports it so (`commands`). Typing into it (`i` in the TUI, `attach --type`) is
typing into its terminal there: this side takes its keyboard on the share for the client
that types here (the share refuses, in its words, a process without a terminal or one that
someone typing on that machine holds), sends the keys there in order, and gives it back.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Coroutine, Mapping
from typing import Any

from ...errors import LaunchError
from ...plan.model import Plan
from ..vocabulary.requests import Input, Status, TakeKeys
from .share_link import Share

STATUS_TIMEOUT = 2.0
"""How long the launching side's `status` waits for a share's (`ls` waits 3 s for it)."""


class ShareRequests:
    """The launching side's requests to the shares of `shares` (by machine name)."""

    def __init__(self, shares: Mapping[str, Share], plan: Callable[[], Plan],
                 spawn: Callable[[Coroutine[Any, Any, Any]], None]) -> None:
        self.shares = shares
        self.plan = plan
        self.spawn = spawn  # a task of the coordinator's own, cancelled when it closes

    def connected(self, process_id: str) -> Share:
        """The share that runs `process_id`, linked now; LaunchError saying why not."""
        machine = self.plan().process(process_id).machine
        share = self.shares.get(machine or "")
        if share is None or share.conn is None:
            why = share.failure if share is not None and share.failure else \
                f"the link to {machine} is lost; connecting again" \
                if share is not None and share.unknown else "not connected"
            raise LaunchError(f"{process_id} runs on {machine}: {why}")
        return share

    async def commands(self) -> dict[str, dict[str, Any]]:
        async def one(share: Share) -> dict[str, dict[str, Any]]:
            try:
                status = await share.ask(Status(resources=False), STATUS_TIMEOUT)
            except LaunchError:
                return {}  # not known now: the launching side says what it can
            return {p.id: p.started_with() for p in status.processes
                    if p.machine == share.machine.name}

        found: dict[str, dict[str, Any]] = {}
        linked = [share for share in self.shares.values() if share.conn is not None]
        for part in await asyncio.gather(*(one(share) for share in linked)):
            found.update(part)
        return found

    async def take_keys(self, process_id: str) -> None:
        share = self.connected(process_id)
        await share.ask(TakeKeys(process_id, on=True))
        share.typing = process_id

    def give_keys(self, process_id: str) -> None:
        machine = self.plan().process(process_id).machine
        share = self.shares.get(machine or "")
        if share is None or share.typing != process_id:
            return
        share.typing = None
        if share.conn is not None:
            self.spawn(self._give_back(share, process_id))

    async def _give_back(self, share: Share, process_id: str) -> None:
        try:
            await share.ask(TakeKeys(process_id, on=False))
        except LaunchError:
            pass  # the link is gone, and with it the keyboard there

    async def type_keys(self, process_id: str, data: bytes) -> int:
        share = self.connected(process_id)
        if share.typing != process_id:
            # the link was made again since the keyboard was taken: the share gave it
            # back when the old one closed; taken again, or refused in its words
            await self.take_keys(process_id)
        result = await share.ask(Input(process_id, data.decode(errors="replace")))
        return int(result.get("dropped") or 0) if isinstance(result, dict) else 0


__all__ = ["ShareRequests"]
