"""Processes placed on other machines (`--machines`): started, stopped and followed there.

A launch placed over several machines runs one share per machine, each a supervisor of the
same plan (both sides resolve the same file with the same arguments, so a process has the
same id everywhere). A supervisor runs the processes placed on its own `machine` and
never spawns the others: on the launching side their start and stop go to `remote` (the
coordinator, run/machines_share.py), and their events come back through `mirror`, so they
drive the same states, consumers and triggers as local ones. On another machine's share
they are "elsewhere", and what they do arrives through `external_event`, so a node there
can wait for a node here.
"""

from __future__ import annotations

import time
from typing import Any, Protocol

from ...errors import LaunchError
from ..events import Event
from .starting import Starting

ELSEWHERE = "elsewhere"
"""The state, in a share, of a process another machine runs."""


class RemoteControl(Protocol):
    """What starts and stops a process on the machine it is placed on."""

    async def forward(self, op: str, process_id: str) -> None:
        """`op` is start, stop or restart; raises LaunchError when the machine cannot be
        asked."""
        ...


class Placed(Starting):
    """Which machine runs each process, and the processes run by another."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.machine: str | None = None
        """The machine whose share this supervisor runs; None: the launching side."""
        self.remote: RemoteControl | None = None
        self._pids_elsewhere: dict[str, int] = {}  # for OnProcessIO events of theirs

    def set_placement(self, machine: str | None, remote: RemoteControl | None) -> None:
        """Before `run`: this side is `machine`'s share; `remote` starts and stops the
        others (the launching side's coordinator), or None (another machine's share, which
        only hears of them)."""
        self.machine = machine
        self.remote = remote
        if remote is None:
            for proc in self.plan.processes:
                if proc.enabled and proc.machine != machine:
                    self.states[proc.id] = ELSEWHERE
        if not self.runs_actions():
            for action in self.plan.actions:
                if action.enabled:
                    self.states[action.id] = ELSEWHERE

    def runs_actions(self) -> bool:
        """The plan's actions (event handlers, service calls, log lines) run once, on the
        launching side, which hears of every process's start and exit; a share runs only
        its processes."""
        return self.machine is None

    def runs_here(self, process_id: str) -> bool:
        """Whether this supervisor spawns it (actions always run where the launch runs)."""
        try:
            return self.plan.process(process_id).machine == self.machine
        except KeyError:
            return True

    async def start(self, process_id: str) -> None:
        if self.runs_here(process_id):
            await super().start(process_id)
        elif self.remote is None:
            self.states[process_id] = ELSEWHERE  # its own machine starts it
        else:
            await self._forward("start", process_id)

    async def stop(self, process_id: str) -> None:
        if self.runs_here(process_id):
            await super().stop(process_id)
        else:
            await self._forward("stop", process_id)

    async def _forward(self, op: str, process_id: str) -> None:
        if self.remote is None:
            where = self.plan.process(process_id).machine or "the launching side"
            raise LaunchError(f"{process_id} runs on {where}: {op} it from the launching "
                              "side")
        await self.remote.forward(op, process_id)

    def mirror(self, event: Event, state: str | None = None) -> None:
        """An event of a process another machine runs, as its share sent it, with the
        state it left it in: told to the consumers and triggers as a local one is."""
        process_id = event.process
        if process_id is None or process_id not in self.states:
            return
        if event.kind == "output":
            self.emit(event)
            if self.io_watchers or self.any_watchers:  # OnProcessIO handlers here
                self.dispatch_io(process_id, event.stream or "stdout", event.lines,
                                 self._pids_elsewhere.get(process_id, 0))
            return
        if event.kind == "started" and event.pid is not None:
            self._pids_elsewhere[process_id] = event.pid
        if state is not None:
            self.states[process_id] = state
        if event.kind == "exited" and event.code is not None:
            self.exit_codes[process_id] = event.code
            requested = bool((event.data or {}).get("requested"))
            if event.code != 0 and not requested and not self.shutting_down:
                self.crashes[process_id] = event.code
                self.crash_times[process_id] = time.monotonic()
        self.emit(event)
        if event.kind == "started":
            self.external_event(process_id, "start", event.pid)
        elif event.kind == "exited":
            self.external_event(process_id, "exit", event.pid, event.code)

    def external_event(self, process_id: str, on: str, pid: int | None = None,
                       code: int | None = None) -> None:
        """A process run elsewhere started (`on` "start") or exited ("exit"): what waits
        for it here (a start-up chain, an OnProcessStart/Exit handler) goes on."""
        if on not in ("start", "exit"):
            raise ValueError(f"an external event is start or exit, not {on!r}")
        if process_id not in {p.id for p in self.plan.processes}:
            raise LaunchError(f"no process {process_id!r} in this launch")
        self.process_event(process_id, on, pid, code)
        self.flag(process_id, on).set()
        self.changed.set()


__all__ = ["ELSEWHERE", "Placed", "RemoteControl"]
