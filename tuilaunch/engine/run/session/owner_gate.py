"""The launch's first process waits for its owner to show the plan (`tuilaunch FILE`).

The TUI of `tuilaunch FILE` does not read the launch file: it starts the session's server at
once, and draws the tree from the plan the server sends (client/served_session.py), so the
file is loaded once per launch, by the server, as ros2 launch loads it. The tree is still
drawn before the first process starts: a server started by such an owner (`OWNER_ENV` set)
starts the plan's processes once the owner says it shows the plan (the `PlanShown`
request), or after `OWNER_WAIT` seconds (a TUI killed before that leaves a launch that
runs, not one that waits forever), or at once when it is asked to stop meanwhile (it then
starts nothing).
`--detach`, `serve FILE` and `--headless` start at once, as before.
"""

from __future__ import annotations

import asyncio
import os

OWNER_ENV = "TUILAUNCH_OWNER_WAITS"
"""Set for a server started by its owning TUI: its processes wait for the plan to show."""
OWNER_WAIT = 10.0
"""Seconds a server waits for its owner to show the plan before it starts the launch anyway:
the owner shows it within a fraction of a second of the server's answer on a quiet machine,
and a second or two on a loaded one."""


class OwnerGate:
    """Open, or closed until the owner shows the plan (`open`) or `wait` seconds passed."""

    def __init__(self, wait: float | None) -> None:
        """`wait`: seconds to wait for the owner at most; None: no owner, open at once."""
        self.wait = wait
        self._opened = asyncio.Event()
        self.timed_out = False
        """The owner did not show the plan in time: the launch started without it."""
        if wait is None:
            self._opened.set()

    @classmethod
    def from_environment(cls) -> OwnerGate:
        """Closed for a server its owner started (`OWNER_ENV`); the variable is taken out
        of the environment, so the launch's processes (a nested launch) never see it."""
        return cls(OWNER_WAIT if os.environ.pop(OWNER_ENV, None) else None)

    def open(self) -> None:
        self._opened.set()

    async def passed(self) -> None:
        """Returns once the gate is open, or its wait is over."""
        if self._opened.is_set():
            return
        try:
            await asyncio.wait_for(self._opened.wait(), self.wait)
        except TimeoutError:
            self.timed_out = True
        self._opened.set()
