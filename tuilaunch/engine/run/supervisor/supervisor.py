"""Run a Plan: start processes, read their output, fire triggers, respawn, shut down.

Each process leads its own process group (its own session); the supervisor signals the
group as one. A watchdog process stops every process of the launch if tuilaunch dies,
however it dies (run/process/watchdog.py). Every output line goes to the process's log file before
any consumer sees it; consumers only get events, and a consumer that fails (a closed stdout,
a dead terminal) never stops the reading of a pipe nor a shutdown.

No thread per child: each child's exit is watched through a pidfd on the event loop, and
its output through non-blocking reads on the same loop.

A concern that owns state of its own is a collaborator the supervisor holds, made and
tested alone: the TriggerBook (triggers.py), the Stopper (stopping.py), the Respawner
(respawn.py), Placing (placed.py). The supervisor's own behaviour over the shared state is
one concern per file, stacked on core.py (state, events): plan_actions.py (triggers waited
for, actions performed), starting.py (a process's start, exit and respawn), interacting.py
(the operator's hands on a process). This file runs the whole, stops, places, and changes
the plan. Plugins (run/plugins.py) add what needs ROS.
"""

from __future__ import annotations

import asyncio
import signal
import time
from pathlib import Path

from ...errors import LaunchError
from ...plan.model import ActionKind, Plan, PlanDiff, diff_plans
from ..events import (
    Consumer,
    Event,
    LaunchEvent,
    Log,
    Output,
    ProcessExited,
    Shutdown,
    Started,
    Stopping,
)
from ..process.readers import Running
from .interacting import Interacting, restart_fields
from .placed import ELSEWHERE, RemoteControl
from .stopping import CTRL_C_REASON, kill_group

ACTION_STOP_S = 5.0
"""How long the shutdown waits for a cancelled action (a call_service waiting for its
service) to end: a well-behaved one ends at once; one that ignores the cancellation must
not hold the launch forever."""

__all__ = ["Consumer", "Event", "LaunchEvent", "Supervisor"]


class Supervisor(Interacting):
    """Runs a plan: see what it is made of (module docstring)."""

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
            said_now = [a for a in self.plan.actions if a.kind == ActionKind.LOG and a.enabled
                        and a.trigger is None and self.runs_actions()]
            for action in said_now:
                self.log_now(action)
            said = {action.id for action in said_now}
            for proc in self.plan.processes:
                if not self.runs_here(proc.id):
                    continue  # its machine's share starts it (placed.py)
                if proc.enabled and proc.trigger is None:
                    self.start_now(proc.id)  # no task per process: start-up at the floor
                elif proc.enabled:
                    self.spawn_task(self.when_ready(proc.trigger, self.start, proc.id))
            for action in self.plan.actions:
                if action.enabled and self.runs_actions() and action.id not in said:
                    self.schedule_action(action)
            while not self._settled():
                self.changed.clear()
                await self.changed.wait()
            if not self.shutting_down and self.triggers.on_shutdown:
                # as launch does when nothing is left to run: OnShutdown handlers see it
                await self.shutdown("idle")
                while not self._settled():
                    self.changed.clear()
                    await self.changed.wait()
        finally:
            await self._finish()
        real = self.stopper.real_crashes(self.crashes, self.crash_times)
        for process_id in set(self.crashes) - set(real):
            if self.states.get(process_id) == "failed":
                self.states[process_id] = "exited"  # the stop's own signal, a hair early
        failed = [item for item, state in self.states.items() if state == "failed"]
        return 1 if failed or real or self.failed_parts else 0

    async def _finish(self) -> None:
        """Whatever ended the run: nothing left running, nothing left open."""
        if self.running:  # cancelled from outside: stop what still runs, quickly
            self.shutting_down = True
            self.stopper.at_least(1)
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
            # exit handlers of the processes being stopped still run, as in launch, and
            # those of the actions stopped as simple_launch stops their nodes
            return not self.running and not self.actions_stopping and \
                not self.triggers.due_in_shutdown(
                    self.plan.actions, self.states, self.detached_actions)
        if self.keep_alive or self.running or self.busy or self.shutdown_requested:
            return False
        if any(state == "running" for state in self.states.values()):
            return False  # an action is waiting for its service or node
        # a pending item can still start only if what it waits for is alive or pending
        waiting = [p.trigger for p in self.plan.processes if self.states[p.id] == "pending"]
        book, states, processes = self.triggers, self.states, self.plan.processes
        return not any(book.can_fire(trigger, states, processes) for trigger in waiting) and \
            not any(book.action_can_fire(a, states, processes) for a in self.plan.actions
                    if states.get(a.id) == "pending")

    async def replace_plan(self, plan: Plan) -> PlanDiff:
        """Relaunch with new argument values: stop what changed, start what is new.

        Processes whose command, environment and parameters are unchanged are left as they
        are (running, finished or waiting for their trigger); triggers of new processes fire
        at once when what they wait for already happened.
        """
        running = {pid for pid in self.running}
        diff = diff_plans(self.plan, plan, running)
        again = set(diff.stop) & set(diff.start)
        self.busy += 1
        self.coming_back |= again
        try:
            await asyncio.gather(*(self.stop(pid) for pid in diff.stop if pid in running))
            old_actions = {(a.kind, a.target, repr(a.data)) for a in self.plan.actions
                           if a.enabled}
            self.plan = plan
            for proc in plan.processes:
                # a kept process keeps its state: finished, failed, or still waiting
                if proc.id not in self.running and proc.id not in diff.keep:
                    self.states[proc.id] = "pending" if proc.enabled else "skipped"
            self.triggers.forget_handlers()
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
            self.coming_back -= again  # they are pending now, or running
            self.changed.set()
        self.set_placement(self.placing.machine, self.placing.remote)  # the new plan's
        return diff

    async def restart(self, process_id: str, prefix: str | None = None,
                      log_level: str | None = None, terminal: bool = False) -> None:
        """Stops and starts one process; `prefix` runs it under a tool (gdb, valgrind) and
        `terminal` gives it a terminal, until a restart without them; `log_level` sets its
        ROS log level until changed (see `restart_options`: checked before anything
        stops)."""
        self.busy += 1  # the run must not look finished between the stop and the start
        self.coming_back.add(process_id)
        try:
            if not self.runs_here(process_id) and self.placing.remote is not None:
                # its machine restarts it, in one request: the tool is looked for on its
                # PATH, and its end there says it comes back (`again`), as one here does
                await self.placing.forward(self.plan, "restart", process_id,
                                           **restart_fields(prefix, log_level, terminal))
                return
            self.restart_options(process_id, prefix, log_level, terminal)
            await self.stop(process_id)
            await self.start(process_id)
        finally:
            self.busy -= 1
            self.coming_back.discard(process_id)
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

    # --- stopping (the escalation is the Stopper's, stopping.py) ----------------------------

    async def stop(self, process_id: str) -> None:
        self.respawner.forget(process_id)
        if not self.runs_here(process_id):
            await self.placing.forward(self.plan, "stop", process_id)
            return
        running = self.running.get(process_id)
        if running is not None:
            running.stopping = True
            await self.escalate(running)
            # reaped is not ended: its last output is read and its end told first, so a
            # start that follows (a restart, a relaunch) finds it gone, not still running
            await running.gone.wait()
        elif process_id in self.respawn_waits:  # between two runs: it does not come back
            self.respawn_waits.pop(process_id).set()
            self.states[process_id] = "exited"
            self.emit(Log(process_id, reason="respawn called off: stopped while it "
                            "waited to come back"))
            self.changed.set()

    async def shutdown(self, reason: str = "shutdown") -> None:
        if self.shutting_down:
            return
        self.shutting_down = True
        self.stopper.began()
        self.stopper.terminal_sigint = reason == CTRL_C_REASON
        try:
            await self.tell_shutdown(reason)
        finally:
            self.actions_stopping = list(self.detached_tasks.values())
            for task in self.actions_stopping:
                task.cancel()
            await asyncio.gather(*(self.escalate(r) for r in list(self.running.values())),
                                 self._actions_stopped(), return_exceptions=True)
            self.changed.set()

    async def _actions_stopped(self) -> None:
        """The cancelled actions have ended (their end, as a node's, fires their exit
        handlers); one that ignores its cancellation holds the run for ACTION_STOP_S."""
        if self.actions_stopping:
            await asyncio.wait(self.actions_stopping, timeout=ACTION_STOP_S)
        self.actions_stopping = []
        self.changed.set()

    async def tell_shutdown(self, reason: str) -> None:
        """The Shutdown event: said, and seen by the OnShutdown handlers. A Shutdown action
        performed while the launch already stops calls this again, as launch emits its
        event again (its handlers see both reasons)."""
        self.emit(Shutdown(reason=reason,
                        data={"launch": True} if reason in self.launch_reasons else None))
        for action in self.triggers.on_shutdown:
            try:
                await self.perform_action(action, LaunchEvent(reason=reason))
            except Exception as exc:  # an OnShutdown action never stops the shutdown
                self.report_io(f"on-shutdown action {action.id} raised "
                               f"{type(exc).__name__}: {exc}")

    def escalate_now(self) -> str | None:
        """The operator insists (a second Ctrl+C): SIGTERM now; once more: SIGKILL.

        Returns the signal's name now sent, or None when nothing is left to stop."""
        if not self.running:
            return None
        sent = self.stopper.insist()
        if not self.shutting_down:
            self.spawn_task(self.shutdown("stop requested again"))
        return sent

    async def escalate(self, running: Running) -> None:
        """SIGINT, then SIGTERM, then SIGKILL, to the process's whole group; it is
        "stopping" until its end is told, for every client, whoever asked."""
        process_id = running.plan.id
        if self.states.get(process_id) == "running":
            self.states[process_id] = "stopping"
            self.emit(Stopping(process_id, pid=running.process.pid))
        await self.stopper.escalate(running)

    def kill_all(self) -> None:
        """Last resort when the caller cannot wait (the UI is being torn down): SIGKILL,
        and the watchdog sweeps what the processes left behind."""
        self.shutting_down = True
        for running in list(self.running.values()):
            kill_group(running.process.pid, signal.SIGKILL)
        self.remove_parameter_files()
        self.watchdog.close()

    def remove_parameter_files(self) -> None:
        for proc in self.plan.processes:
            for path, _ in proc.generated_parameter_files:
                Path(path).unlink(missing_ok=True)
        try:
            self.plan.params_dir.rmdir()
        except OSError:
            pass

    # --- placement over machines (which side runs what is Placing's, placed.py) -------------

    def set_placement(self, machine: str | None, remote: RemoteControl | None) -> None:
        """Before `run`: this side is `machine`'s share; `remote` starts and stops the
        others (the launching side's coordinator), or None (another machine's share, which
        only hears of them)."""
        for item_id in self.placing.place(machine, remote, self.plan):
            self.states[item_id] = ELSEWHERE

    @property
    def machine(self) -> str | None:
        """The machine whose share this supervisor runs; None: the launching side."""
        return self.placing.machine

    def runs_actions(self) -> bool:
        return self.placing.runs_actions()

    def runs_here(self, process_id: str) -> bool:
        """Whether this supervisor spawns it (actions always run where the launch runs)."""
        return self.placing.runs_here(self.plan, process_id)

    async def start(self, process_id: str, respawn: bool = False) -> None:
        """Starts one process (also a stopped or exited one, from the UI), here or on its
        machine; `respawn`: it comes back after a crash, counted by the Respawner (an
        operator's start counts from zero again)."""
        if not respawn:
            self.respawner.forget(process_id)
        waiting = self.respawn_waits.pop(process_id, None)
        if waiting is not None:
            waiting.set()  # started now by the operator: the respawn under way is moot
        ending = self.running.get(process_id)
        if ending is not None and ending.exited.done():
            await ending.gone.wait()  # it exited on its own a moment ago: its end first
        if self.runs_here(process_id):
            self.start_now(process_id)
        elif self.placing.remote is None:
            self.states[process_id] = ELSEWHERE  # its own machine starts it
        else:
            await self.placing.forward(self.plan, "start", process_id)

    def mirror(self, event: Event, state: str | None = None) -> None:
        """An event of a process another machine runs, as its share sent it, with the
        state it left it in: told to the consumers and triggers as a local one is."""
        process_id = event.process
        if process_id is None or process_id not in self.states:
            return
        if isinstance(event, Output):
            self.emit(event)
            if self.triggers.watches_output:  # OnProcessIO handlers here
                self.dispatch_io(process_id, event.stream or "stdout", event.lines,
                                 self.placing.pids_elsewhere.get(process_id, 0))
            return
        if isinstance(event, Started) and event.pid is not None:
            self.placing.pids_elsewhere[process_id] = event.pid
        if state is not None:
            self.states[process_id] = state
        if isinstance(event, ProcessExited) and event.code is not None:
            self.exit_codes[process_id] = event.code
            if event.crashed and not self.shutting_down:  # as its machine decided
                self.crashes[process_id] = event.code
                self.crash_times[process_id] = time.monotonic()
        self.emit(event)
        if isinstance(event, Started):
            self.external_event(process_id, "start", event.pid)
        elif isinstance(event, ProcessExited):
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
