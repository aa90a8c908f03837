"""Ending processes: one stopped (`stop`), the whole launch (`shutdown`, `escalate_now`),
and the last resort when nobody can wait (`kill_all`).

The escalation itself (SIGINT, SIGTERM, SIGKILL, how hard the shutdown stops) is the
Stopper's (stopping.py); this decides what is stopped, and when the launch's shutdown is
said to its OnShutdown handlers (`actions`, plan_actions.py).
"""

from __future__ import annotations

import asyncio
import signal
from pathlib import Path

from ..events import Log, Stopping
from ..process.readers import Running
from ..vocabulary.requests import Stop
from .core import SupervisorCore
from .plan_actions import PlanActions
from .stopping import CTRL_C_REASON, kill_group

ACTION_STOP_S = 5.0
"""How long the shutdown waits for a cancelled action (a call_service waiting for its
service) to end: a well-behaved one ends at once; one that ignores the cancellation must
not hold the launch forever."""


class Ending:
    """Stopping a process, shutting the launch down, and killing what is left."""

    def __init__(self, core: SupervisorCore, actions: PlanActions) -> None:
        self.core = core
        self.actions = actions

    async def stop(self, process_id: str) -> None:
        core = self.core
        core.respawner.forget(process_id)
        if not core.runs_here(process_id):
            await core.placing.forward(core.plan, Stop(process_id))
            return
        running = core.running.get(process_id)
        if running is not None:
            running.stopping = True
            await self.escalate(running)
            # reaped is not ended: its last output is read and its end told first, so a
            # start that follows (a restart, a relaunch) finds it gone, not still running
            await running.gone.wait()
        elif (wait := core.records[process_id].respawn_wait) is not None:
            # between two runs: it does not come back
            core.records[process_id].respawn_wait = None
            wait.set()
            core.states[process_id] = "exited"
            core.emit(Log(process_id, reason="respawn called off: stopped while it "
                          "waited to come back"))
            core.changed.set()

    async def shutdown(self, reason: str = "shutdown") -> None:
        core = self.core
        if core.shutting_down:
            return
        core.shutting_down = True
        core.stopper.began()
        core.stopper.terminal_sigint = reason == CTRL_C_REASON
        try:
            await self.actions.tell_shutdown(reason)
        finally:
            core.actions_stopping = list(core.detached_tasks.values())
            for task in core.actions_stopping:
                task.cancel()
            await asyncio.gather(*(self.escalate(r) for r in list(core.running.values())),
                                 self._actions_stopped(), return_exceptions=True)
            core.changed.set()

    async def _actions_stopped(self) -> None:
        """The cancelled actions have ended (their end, as a node's, fires their exit
        handlers); one that ignores its cancellation holds the run for ACTION_STOP_S."""
        core = self.core
        if core.actions_stopping:
            await asyncio.wait(core.actions_stopping, timeout=ACTION_STOP_S)
        core.actions_stopping = []
        core.changed.set()

    def escalate_now(self) -> str | None:
        """The operator insists (a second Ctrl+C): SIGTERM now; once more: SIGKILL.

        Returns the signal's name now sent, or None when nothing is left to stop."""
        core = self.core
        if not core.running:
            return None
        sent = core.stopper.insist()
        if not core.shutting_down:
            core.spawn_task(self.shutdown("stop requested again"))
        return sent

    async def escalate(self, running: Running) -> None:
        """SIGINT, then SIGTERM, then SIGKILL, to the process's whole group; it is
        "stopping" until its end is told, for every client, whoever asked."""
        core = self.core
        process_id = running.plan.id
        if core.states.get(process_id) == "running":
            core.states[process_id] = "stopping"
            core.emit(Stopping(process_id, pid=running.process.pid))
        await core.stopper.escalate(running)

    def kill_all(self) -> None:
        """Last resort when the caller cannot wait (the UI is being torn down): SIGKILL,
        and the watchdog sweeps what the processes left behind."""
        core = self.core
        core.shutting_down = True
        for running in list(core.running.values()):
            kill_group(running.process.pid, signal.SIGKILL)
        self.remove_parameter_files()
        core.watchdog.close()

    def remove_parameter_files(self) -> None:
        plan = self.core.plan
        for proc in plan.processes:
            for path, _ in proc.generated_parameter_files:
                Path(path).unlink(missing_ok=True)
        try:
            plan.params_dir.rmdir()
        except OSError:
            pass
