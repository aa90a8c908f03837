"""`]` and `[` pressed faster than a lifecycle node moves (`]]` from unconfigured: configure,
then activate). Each step is picked from the state the node will be in once the steps asked
before it are done, and the steps are asked one after the other: a lifecycle node refuses a
transition while another runs."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable

AFTER = {"configure": "inactive", "activate": "active", "deactivate": "inactive",
         "cleanup": "unconfigured"}
"""The state a step leads to (the primary states of the managed-node design)."""

STEPS = {"up": {"unconfigured": "configure", "inactive": "activate"},
         "down": {"active": "deactivate", "inactive": "cleanup"}}
"""What `]` (up) and `[` (down) ask of a node in a state."""


class LifecycleSteps:
    """The operator's lifecycle steps of each node, in the order asked (on the UI's loop)."""

    def __init__(self) -> None:
        self.ahead: dict[str, str] = {}  # the state once the steps asked are done
        self._pending: dict[str, int] = {}
        self._locks: dict[str, asyncio.Lock] = {}

    def step(self, process: str, reported: str | None, direction: str) -> str | None:
        """The transition `direction` asks of `process`, whose events say `reported`."""
        ahead = self.ahead.get(process)
        if ahead is not None and ahead == reported and process not in self._pending:
            del self.ahead[process]  # the node's events caught up: they say it from here
            ahead = None
        return STEPS[direction].get(ahead or reported or "")

    def take(self, process: str, transition: str,
             request: Callable[[], Awaitable[bool]]) -> Awaitable[bool]:
        """Notes the step now (a key pressed next picks the one after it), and returns what
        asks `request()` once the steps asked before it are done."""
        self._pending[process] = self._pending.get(process, 0) + 1
        if transition in AFTER:
            self.ahead[process] = AFTER[transition]
        return self._in_turn(process, request)

    async def _in_turn(self, process: str, request: Callable[[], Awaitable[bool]]) -> bool:
        lock = self._locks.setdefault(process, asyncio.Lock())
        made = False
        try:
            async with lock:
                made = await request()
                return made
        finally:
            self._pending[process] -= 1
            if not self._pending[process]:
                del self._pending[process]
                if not made:  # refused or failed: where it is, its events say
                    self.ahead.pop(process, None)
                # made: the state it leads to holds until the node's events say it too (the
                # answer may come before them), so a key typed meanwhile steps from there
