"""Run a Plan: start processes, read their output, fire triggers, respawn, shut down.

Each process leads its own process group (its own session); the supervisor signals the
group as one. A watchdog process stops every process of the launch if tuilaunch dies,
however it dies (run/watchdog.py). Every output line goes to the process's log file before
any consumer sees it; consumers only get events, and a consumer that fails (a closed stdout,
a dead terminal) never stops the reading of a pipe nor a shutdown.

No thread per child: each child's exit is watched through a pidfd on the event loop, and
its output through non-blocking reads on the same loop.

The work is split by concern, one file each, stacked as layers of one class: core.py
(state, events), triggers.py, plan_actions.py, stopping.py, respawn.py, starting.py,
interacting.py; this file runs the whole and changes the plan. Plugins (run/plugins.py)
add what needs ROS.
"""

from __future__ import annotations

import asyncio
import time

from ...plan.model import Plan, PlanDiff, diff_plans
from ..events import Consumer, Event, LaunchEvent
from .interacting import Interacting
from .placed import Placed

__all__ = ["Consumer", "Event", "LaunchEvent", "Supervisor"]


class Supervisor(Interacting, Placed):
    """Runs a plan: see the layers it is made of (module docstring)."""

    async def run(self, keep_alive: bool = False) -> int:
        """Runs until nothing can happen any more, or shutdown; returns an exit status.

        0 when every process ended well or was stopped on request (whatever signal it died
        of); 1 when a process could not start or exited on its own with a failure.

        With keep_alive (an interactive UI), only shutdown ends the run: an operator who
        stops every process still wants to start them again."""
        self.keep_alive = keep_alive
        try:
            for plugin in self.plugins:
                begun = plugin.run_started()
                if begun is not None:
                    self.spawn_task(begun)
            for proc in self.plan.processes:
                if not self.runs_here(proc.id):
                    continue  # its machine's share starts it (run/placed.py)
                if proc.enabled and proc.trigger is None:
                    self.start_now(proc.id)  # no task per process: start-up at the floor
                elif proc.enabled:
                    self.spawn_task(self.when_ready(proc.trigger, self.start, proc.id))
            for action in self.plan.actions:
                if action.enabled and self.runs_actions():
                    self.schedule_action(action)
            while not self._settled():
                self.changed.clear()
                await self.changed.wait()
            if not self.shutting_down and self.on_shutdown:
                # as launch does when nothing is left to run: OnShutdown handlers see it
                await self.shutdown("idle")
                while not self._settled():
                    self.changed.clear()
                    await self.changed.wait()
        finally:
            await self._finish()
        real = self.real_crashes()
        for process_id in set(self.crashes) - set(real):
            if self.states.get(process_id) == "failed":
                self.states[process_id] = "exited"  # the stop's own signal, a hair early
        failed = [item for item, state in self.states.items() if state == "failed"]
        return 1 if failed or real or self.failed_parts else 0

    async def _finish(self) -> None:
        """Whatever ended the run: nothing left running, nothing left open."""
        if self.running:  # cancelled from outside: stop what still runs, quickly
            self.shutting_down = True
            self.urgency = max(self.urgency, 1)
            await asyncio.gather(*(self.escalate(r) for r in list(self.running.values())),
                                 return_exceptions=True)
        await self._drain()
        for reader in list(self.lingering):
            reader.close()
        for plugin in self.plugins:
            try:
                await plugin.close()
            except Exception as exc:  # a plugin that fails to close never stops the end
                self.report_io(f"{type(plugin).__name__} failed to close: "
                               f"{type(exc).__name__}: {exc}")
        self.launch_log.close()
        self.remove_parameter_files()
        # the watchdog stops what a node left behind (daemons, stray group members)
        self.watchdog.close()
        deadline = time.monotonic() + self.watchdog.grace + 3.0
        while not self.watchdog.finished() and time.monotonic() < deadline:
            await asyncio.sleep(0.02)

    def _settled(self) -> bool:
        if self.shutting_down:
            # waiting actions, timers and respawns are cancelled when the run drains;
            # exit handlers of the processes being stopped still run, as in launch
            return not self.running and not self.actions_due_in_shutdown()
        if self.keep_alive or self.running or self.busy or self.shutdown_requested:
            return False
        if any(state == "running" for state in self.states.values()):
            return False  # an action is waiting for its service or node
        # a pending item can still start only if what it waits for is alive or pending
        waiting = [p.trigger for p in self.plan.processes if self.states[p.id] == "pending"]
        return not any(self.can_fire(trigger) for trigger in waiting) and not any(
            self.action_can_fire(a) for a in self.plan.actions
            if self.states.get(a.id) == "pending")

    async def replace_plan(self, plan: Plan) -> PlanDiff:
        """Relaunch with new argument values: stop what changed, start what is new.

        Processes whose command, environment and parameters are unchanged are left as they
        are (running, finished or waiting for their trigger); triggers of new processes fire
        at once when what they wait for already happened.
        """
        running = {pid for pid in self.running}
        diff = diff_plans(self.plan, plan, running)
        self.busy += 1
        try:
            await asyncio.gather(*(self.stop(pid) for pid in diff.stop if pid in running))
            old_actions = {(a.kind, a.target, repr(a.data)) for a in self.plan.actions
                           if a.enabled}
            self.plan = plan
            for proc in plan.processes:
                # a kept process keeps its state: finished, failed, or still waiting
                if proc.id not in self.running and proc.id not in diff.keep:
                    self.states[proc.id] = "pending" if proc.enabled else "skipped"
            self.io_watchers.clear()
            self.on_shutdown.clear()
            self.any_watchers.clear()
            for proc in plan.processes:
                if proc.id in diff.start and self.runs_here(proc.id):
                    self.spawn_task(self.when_ready(proc.trigger, self.start, proc.id))
            for action in plan.actions:
                self.states.setdefault(action.id, "pending" if action.enabled else "skipped")
                fresh = (action.kind, action.target, repr(action.data)) not in old_actions
                on_event = action.trigger is not None and action.trigger.on in ("io", "shutdown")
                # event watchers were cleared above and come back; one-off actions rerun
                # only when they are new or their target or data changed
                if action.enabled and (fresh or on_event) and self.runs_actions():
                    self.schedule_action(action)
        finally:
            self.busy -= 1
            self.changed.set()
        self.set_placement(self.machine, self.remote)  # the new plan's placement
        return diff

    async def restart(self, process_id: str, prefix: str | None = None,
                      log_level: str | None = None) -> None:
        """Stops and starts one process; `prefix` runs it under a tool (gdb, valgrind) until
        a restart without one, `log_level` sets its ROS log level until changed (see
        `restart_options`: checked before anything stops)."""
        self.restart_options(process_id, prefix, log_level)
        self.busy += 1  # the run must not look finished between the stop and the start
        try:
            await self.stop(process_id)
            await self.start(process_id)
        finally:
            self.busy -= 1
            self.changed.set()

    async def run_action(self, action_id: str) -> None:
        """Performs one action of the plan again (the UI restarted its group)."""
        action = next((a for a in self.plan.actions if a.id == action_id), None)
        if action is None or not action.enabled or self.shutting_down:
            return
        self.busy += 1
        try:
            await self.perform_action(action)
        finally:
            self.busy -= 1
            self.changed.set()

    async def _drain(self) -> None:
        for task in list(self.tasks):
            if not task.done():
                task.cancel()
        await asyncio.gather(*self.tasks, return_exceptions=True)
