"""Processes placed on other machines (`--machines`): which side runs what.

A launch placed over several machines runs one share per machine, each a supervisor of the
same plan (both sides resolve the same file with the same arguments, so a process has the
same id everywhere). A supervisor runs the processes placed on its own `machine` and
never spawns the others: on the launching side their start and stop go to `remote` (the
coordinator, run/machines/machines_share.py), and their events come back through
`Supervisor.mirror`, so they drive the same states, consumers and triggers as local ones.
On another machine's share they are "elsewhere", and what they do arrives through
`Supervisor.external_event`, so a node there can wait for a node here.

`Placing` owns this side's machine, its remote control and the pids of processes run
elsewhere; the supervisor's parts ask it (core.py holds it). The remote control also says
how its machine started each process (the launching side's `status`) and types into them
there (`i`, `attach --type`), so a terminal node placed elsewhere is reached as one here.
Made and tested alone: tests/integration/test_supervisor_parts.py.
"""

from __future__ import annotations

from typing import Any, Protocol

from ...errors import LaunchError
from ...plan.model import Plan
from ..vocabulary.requests import Restart, Start, Stop

ELSEWHERE = "elsewhere"
"""The state, in a share, of a process another machine runs."""
UNKNOWN = "unknown"
"""The state, on the launching side, of a process whose machine's link is lost: it may run
on there, or not; nobody here can say until the link is back."""


class RemoteKeys(Protocol):
    """What types into a process on the machine it is placed on, and asks what it was
    started with."""

    async def commands(self) -> dict[str, dict[str, Any]]:
        """What each process placed elsewhere was started with, as its machine's `status`
        says it (command, command_line, env, terminal), for the machines that answer now."""
        ...

    async def take_keys(self, process_id: str) -> None:
        """Takes the keyboard of `process_id` on its machine for this side (LaunchError, its
        machine's words, when it cannot be typed into there)."""
        ...

    def give_keys(self, process_id: str) -> None:
        """Gives that keyboard back (in the background: a link that is gone gave it back)."""
        ...

    async def type_keys(self, process_id: str, data: bytes) -> int:
        """Types `data` into `process_id` on its machine; the bytes it dropped."""
        ...


class RemoteControl(Protocol):
    """What starts and stops a process on the machine it is placed on."""

    async def forward(self, request: Start | Stop | Restart) -> None:
        """Asks the process's machine to start, stop or restart it (the session's own
        request, a restart with its prefix, log_level, terminal); raises LaunchError when
        the machine cannot be asked."""
        ...

    @property
    def requests(self) -> RemoteKeys:
        """What asks the other machines for their processes' keyboards and commands."""
        ...


class Placing:
    """Which machine this supervisor is, and who starts the processes of the others."""

    def __init__(self) -> None:
        self.machine: str | None = None
        """The machine whose share this supervisor runs; None: the launching side."""
        self.remote: RemoteControl | None = None
        self.pids_elsewhere: dict[str, int] = {}
        """Pids of processes run elsewhere, for OnProcessIO events of theirs."""

    def place(self, machine: str | None, remote: RemoteControl | None,
              plan: Plan) -> list[str]:
        """This side is `machine`'s share; `remote` starts and stops the others, or None.
        Returns the ids of the plan's processes and actions that are elsewhere from here."""
        self.machine = machine
        self.remote = remote
        elsewhere = []
        if remote is None:
            elsewhere += [p.id for p in plan.processes if p.enabled and p.machine != machine]
        if not self.runs_actions():
            elsewhere += [a.id for a in plan.actions if a.enabled]
        return elsewhere

    def runs_actions(self) -> bool:
        """The plan's actions (event handlers, service calls, log lines) run once, on the
        launching side, which hears of every process's start and exit; a share runs only
        its processes."""
        return self.machine is None

    def runs_here(self, plan: Plan, process_id: str) -> bool:
        """Whether this supervisor spawns it (actions always run where the launch runs)."""
        try:
            return plan.process(process_id).machine == self.machine
        except KeyError:
            return True

    async def forward(self, plan: Plan, request: Start | Stop | Restart) -> None:
        """Asks the process's machine to do it; LaunchError from a share (which cannot)."""
        if self.remote is None:
            where = plan.process(request.process).machine or "the launching side"
            raise LaunchError(f"{request.process} runs on {where}: {request.op} it from the "
                              "launching side")
        await self.remote.forward(request)

    def keys_of(self, plan: Plan, process_id: str) -> RemoteKeys:
        """Who types into `process_id`, run elsewhere: the launching side's remote control's
        requests (the keys go to the machine that runs it); LaunchError from a share."""
        if self.remote is None:
            where = plan.process(process_id).machine or "the launching side"
            raise LaunchError(f"{process_id} runs on {where}: type into it from there or "
                              "from the launching side")
        return self.remote.requests


__all__ = ["ELSEWHERE", "UNKNOWN", "Placing", "RemoteControl", "RemoteKeys"]
