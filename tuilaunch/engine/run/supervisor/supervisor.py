"""Run a Plan: start processes, read their output, fire triggers, respawn, shut down.

Each process leads its own process group (its own session); the supervisor signals the
group as one. A watchdog process stops every process of the launch if tuilaunch dies,
however it dies (run/process/watchdog.py). Every output line goes to the process's log file before
any consumer sees it; consumers only get events, and a consumer that fails (a closed stdout,
a dead terminal) never stops the reading of a pipe nor a shutdown.

No thread per child: each child's exit is watched through a pidfd on the event loop, and
its output through non-blocking reads on the same loop.

The Supervisor is made of parts, each made and tested alone: the state every part shares
and the events out (`core`, core.py, with its collaborators: the TriggerBook, the Stopper,
the Respawner, Placing), and the behaviours over that state, each handed the others it
calls: `actions` (PlanActions, plan_actions.py: triggers waited for, actions performed),
`starting` (Starting, starting.py: a process's start, exit and respawn), `ending` (Ending,
ending.py: a stop, the shutdown), `hands` (Interacting, interacting.py: the operator's hands
on a process). This file makes and wires them, runs the whole, places, and changes the
plan; its public verbs and state are what the session server, the headless printer and the
plugins use. Plugins (run/plugins.py) add what needs ROS.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ...errors import LaunchError
from ...plan.model import ActionKind, Plan, PlanDiff, diff_plans
from ..events import Consumer, Event, LaunchEvent, Output, ProcessExited, Started
from ..plugins import SupervisorPlugin
from ..process.readers import Running
from ..vocabulary.forward import Forward
from ..vocabulary.requests import Restart
from .core import SupervisorCore
from .ending import Ending
from .interacting import Interacting
from .placed import ELSEWHERE, UNKNOWN, RemoteControl
from .plan_actions import PlanActions
from .starting import Starting

__all__ = ["Consumer", "Event", "LaunchEvent", "Supervisor"]


class Supervisor:
    """Runs a plan: see what it is made of (module docstring)."""

    def __init__(self, plan: Plan, log_dir: Path, sigterm_timeout: float = 5.0,
                 sigkill_timeout: float = 5.0,
                 plugins: Iterable[SupervisorPlugin] = ()) -> None:
        """`plugins` (run/plugins.py) add what `run` does not know: ROS actions, lifecycle
        nodes, components. engine/launcher.py makes a supervisor with the ROS ones."""
        self.core = SupervisorCore(plan, log_dir, sigterm_timeout, sigkill_timeout, plugins)
        # the supervisor's verbs, looked up when called: starting and ending, which own
        # them, are made after the actions and are handed them, so neither holds the other
        self.actions = PlanActions(self.core, start=self.start, stop=self.stop,
                                   shutdown=self.shutdown)
        self.starting = Starting(self.core, self.actions)
        self.ending = Ending(self.core, self.actions)
        self.hands = Interacting(self.core, self.starting)

    # --- the state others read (the core's) ---------------------------------------------------

    plan = Forward[Plan]("core")
    states = Forward[dict[str, str]]("core", doc="Each process's and action's state, by id.")
    running = Forward[dict[str, Running]]("core", doc="The processes that run now, by id.")
    shutting_down = Forward[bool]("core")
    failed_parts = Forward[set[str]](
        "core", doc="What failed inside a process (a component), by id: the launch ends non-zero.")
    retries = Forward[dict[str, int]]("core", doc="Respawns of each process so far.")
    busy = Forward[int](
        "core", doc="Triggers sleeping or respawns scheduled: the run is not over while any is.")
    log_dir = Forward[Path]("core")
    plugins = Forward[list[SupervisorPlugin]]("core")

    @property
    def exit_codes(self) -> dict[str, int]:
        """Each process's last exit status."""
        return self.core.records.having("exit_code")

    @property
    def deaths(self) -> dict[str, dict[str, str]]:
        """A crash's `signal` name and `core` location, until the process starts again."""
        return self.core.records.having("death")

    @property
    def coming_back(self) -> set[str]:
        """Processes stopped to be started again (a restart, a relaunch)."""
        return set(self.core.records.having("coming_back"))

    @property
    def respawn_waits(self) -> dict[str, asyncio.Event]:
        """Processes waiting out their respawn delay."""
        return self.core.records.having("respawn_wait")

    # --- how the world hears of the launch, and plugs into it (the core's) --------------------

    def subscribe(self, consumer: Consumer) -> None:
        self.core.subscribe(consumer)

    def emit(self, event: Event) -> None:
        """Tells every consumer; one that raises is reported once and never stops us."""
        self.core.emit(event)

    def log(self, text: str, level: str = "INFO") -> None:
        """A line for the launch pane and launch.log from whoever runs the supervisor."""
        self.core.log(text, level)

    def add_plugin(self, plugin: SupervisorPlugin) -> None:
        """Plugs in before `run`: its action kinds join those the supervisor performs."""
        self.core.add_plugin(plugin)

    def state_reached(self, process_id: str, what: str) -> None:
        """A lifecycle transition matching `what`, as a plugin reports it (plan_actions.py)."""
        self.actions.state_reached(process_id, what)

    # --- the verbs on processes (the parts') --------------------------------------------------

    async def start(self, process_id: str, respawn: bool = False) -> None:
        """Starts one process, here or on its machine (starting.py)."""
        await self.starting.start(process_id, respawn)

    async def stop(self, process_id: str) -> None:
        """Stops one process; returns once its end is told (ending.py)."""
        await self.ending.stop(process_id)

    async def shutdown(self, reason: str = "shutdown") -> None:
        """Ends the launch: the Shutdown event, then every process stopped (ending.py)."""
        await self.ending.shutdown(reason)

    def escalate_now(self) -> str | None:
        """The operator insists: the next signal now; None when nothing is left to stop."""
        return self.ending.escalate_now()

    def kill_all(self) -> None:
        """SIGKILL to every process, for a caller that cannot wait."""
        self.ending.kill_all()

    def write_input(self, process_id: str, data: bytes) -> int:
        """Types `data` into a running process's terminal (interacting.py)."""
        return self.hands.write_input(process_id, data)

    async def take_keys(self, process_id: str) -> None:
        """LaunchError unless it can be typed into, here or on its machine (interacting.py)."""
        await self.hands.take_keys(process_id)

    def give_keys(self, process_id: str) -> None:
        """Nobody types into it any more (interacting.py)."""
        self.hands.give_keys(process_id)

    async def type_keys(self, process_id: str, data: bytes) -> int:
        """Types into it, here or on its machine; the bytes dropped (interacting.py)."""
        return await self.hands.type_keys(process_id, data)

    def command_of(self, process_id: str) -> dict[str, Any]:
        """The command, command line and env of the process's last start (interacting.py)."""
        return self.hands.command_of(process_id)

    async def commands_elsewhere(self) -> dict[str, dict[str, Any]]:
        """`command_of` of the processes placed on other machines, as those machines say
        it (a tool, a terminal given there by a restart are theirs to know), for the ones
        that answer now: the launching side's `status` reports them."""
        remote = self.core.placing.remote
        return {} if remote is None else await remote.requests.commands()

    # --- the run ------------------------------------------------------------------------------

    async def run(self, keep_alive: bool = False) -> int:
        """Runs until nothing can happen any more, or shutdown; returns an exit status.

        0 when every process ended well or was stopped on request (whatever signal it died
        of); 1 when a process could not start or exited on its own with a failure.

        With keep_alive (an interactive UI), only shutdown ends the run: an operator who
        stops every process still wants to start them again."""
        core = self.core
        core.keep_alive = keep_alive
        runs_actions = core.placing.runs_actions()
        try:
            for plugin in core.plugins:
                begun = plugin.run_started()
                if begun is not None:
                    core.spawn_task(begun)
            said_now = [a for a in core.plan.actions if a.kind == ActionKind.LOG and a.enabled
                        and a.trigger is None and runs_actions]
            for action in said_now:
                self.actions.log_now(action)
            said = {action.id for action in said_now}
            for proc in core.plan.processes:
                if not core.runs_here(proc.id):
                    continue  # its machine's share starts it (placed.py)
                if proc.enabled and proc.trigger is None:
                    self.starting.start_now(proc.id)  # no task per process: start-up at the floor
                elif proc.enabled:
                    core.spawn_task(self.actions.when_ready(proc.trigger, self.start, proc.id))
            for action in core.plan.actions:
                if action.enabled and runs_actions and action.id not in said:
                    self.actions.schedule_action(action)
            while not self._settled():
                core.changed.clear()
                await core.changed.wait()
            if not core.shutting_down and core.triggers.on_shutdown:
                # as launch does when nothing is left to run: OnShutdown handlers see it
                await self.shutdown("idle")
                while not self._settled():
                    core.changed.clear()
                    await core.changed.wait()
        finally:
            await self._finish()
        crashes = core.records.having("crash_code")
        real = core.stopper.real_crashes(crashes, core.records.having("crash_time"))
        for process_id in set(crashes) - set(real):
            if core.states.get(process_id) == "failed":
                core.states[process_id] = "exited"  # the stop's own signal, a hair early
        failed = [item for item, state in core.states.items() if state == "failed"]
        return 1 if failed or real or core.failed_parts else 0

    async def _finish(self) -> None:
        """Whatever ended the run: nothing left running, nothing left open."""
        core = self.core
        if core.running:  # cancelled from outside: stop what still runs, quickly
            core.shutting_down = True
            core.stopper.at_least(1)
            await asyncio.gather(*(self.ending.escalate(r) for r in list(core.running.values())),
                                 return_exceptions=True)
        await self._drain()
        for reader in list(core.lingering):
            reader.close()
        for plugin in core.plugins:
            try:
                await plugin.close()
            except Exception as exc:  # a plugin that fails to close never stops the end
                core.report_io(f"{type(plugin).__name__} failed to close: "
                               f"{type(exc).__name__}: {exc}")
        core.launch_log.close()
        self.ending.remove_parameter_files()
        # the watchdog stops what a node left behind (daemons, stray group members)
        core.watchdog.close()
        deadline = time.monotonic() + core.watchdog.grace + 3.0
        while not core.watchdog.finished() and time.monotonic() < deadline:
            await asyncio.sleep(0.02)

    def _settled(self) -> bool:
        core = self.core
        book, states, processes = core.triggers, core.states, core.plan.processes
        if core.shutting_down:
            # waiting actions, timers and respawns are cancelled when the run drains;
            # exit handlers of the processes being stopped still run, as in launch, and
            # those of the actions stopped as simple_launch stops their nodes
            return not core.running and not core.actions_stopping and \
                not book.due_in_shutdown(core.plan.actions, states, core.detached_actions)
        if core.keep_alive or core.running or core.busy or core.shutdown_requested:
            return False
        if any(state in ("running", UNKNOWN) for state in states.values()):
            # an action is waiting for its service or node; a process whose machine's link
            # is lost may run on there (machines_share.py connects again)
            return False
        # a pending item can still start only if what it waits for is alive or pending
        waiting = [p.trigger for p in processes if states[p.id] == "pending"]
        return not any(book.can_fire(trigger, states, processes) for trigger in waiting) and \
            not any(book.action_can_fire(a, states, processes) for a in core.plan.actions
                    if states.get(a.id) == "pending")

    async def _drain(self) -> None:
        for task in list(self.core.tasks):
            if not task.done():
                task.cancel()
        await asyncio.gather(*self.core.tasks, return_exceptions=True)

    # --- changing what runs ---------------------------------------------------------------------

    async def replace_plan(self, plan: Plan) -> PlanDiff:
        """Relaunch with new argument values: stop what changed, start what is new.

        Processes whose command, environment and parameters are unchanged are left as they
        are (running, finished or waiting for their trigger); triggers of new processes fire
        at once when what they wait for already happened.
        """
        core = self.core
        running = {pid for pid in core.running}
        diff = diff_plans(core.plan, plan, running)
        again = set(diff.stop) & set(diff.start)
        core.busy += 1
        for process_id in again:
            core.records[process_id].coming_back = True
        try:
            await asyncio.gather(*(self.stop(pid) for pid in diff.stop if pid in running))
            old_actions = {(a.kind, a.target, repr(a.data)) for a in core.plan.actions
                           if a.enabled}
            core.plan = plan
            for proc in plan.processes:
                # a kept process keeps its state: finished, failed, or still waiting
                if proc.id not in core.running and proc.id not in diff.keep:
                    core.states[proc.id] = "pending" if proc.enabled else "skipped"
            core.triggers.forget_handlers()
            for proc in plan.processes:
                if proc.id in diff.start and core.runs_here(proc.id):
                    core.spawn_task(self.actions.when_ready(proc.trigger, self.start, proc.id))
            for action in plan.actions:
                core.states.setdefault(action.id, "pending" if action.enabled else "skipped")
                fresh = (action.kind, action.target, repr(action.data)) not in old_actions
                on_event = action.trigger is not None and action.trigger.on in ("io", "shutdown")
                # event watchers were cleared above and come back; one-off actions rerun
                # only when they are new or their target or data changed
                if action.enabled and (fresh or on_event) and core.placing.runs_actions():
                    self.actions.schedule_action(action)
        finally:
            core.busy -= 1
            for process_id in again:  # they are pending now, or running
                core.records[process_id].coming_back = False
            core.changed.set()
        self.set_placement(core.placing.machine, core.placing.remote)  # the new plan's
        return diff

    async def restart(self, process_id: str, prefix: str | None = None,
                      log_level: str | None = None, terminal: bool = False) -> None:
        """Stops and starts one process; `prefix` runs it under a tool (gdb, valgrind) and
        `terminal` gives it a terminal, until a restart without them; `log_level` sets its
        ROS log level until changed (see `Interacting.restart_options`: checked before
        anything stops)."""
        core = self.core
        core.busy += 1  # the run must not look finished between the stop and the start
        core.records[process_id].coming_back = True
        try:
            if not core.runs_here(process_id) and core.placing.remote is not None:
                # its machine restarts it, in one request: the tool is looked for on its
                # PATH, and its end there says it comes back (`again`), as one here does
                await core.placing.forward(core.plan, Restart(process_id, prefix, log_level,
                                                              terminal))
                return
            self.hands.restart_options(process_id, prefix, log_level, terminal)
            await self.stop(process_id)
            await self.start(process_id)
        finally:
            core.busy -= 1
            core.records[process_id].coming_back = False
            core.changed.set()

    async def run_action(self, action_id: str) -> None:
        """Performs one action of the plan again (the UI restarted its group)."""
        core = self.core
        action = next((a for a in core.plan.actions if a.id == action_id), None)
        if action is None or not action.enabled or core.shutting_down:
            return
        core.busy += 1
        try:
            await self.actions.perform_action(action)
        finally:
            core.busy -= 1
            core.changed.set()

    # --- placement over machines (which side runs what is Placing's, placed.py) -------------

    def set_placement(self, machine: str | None, remote: RemoteControl | None) -> None:
        """Before `run`: this side is `machine`'s share; `remote` starts and stops the
        others (the launching side's coordinator), or None (another machine's share, which
        only hears of them)."""
        for item_id in self.core.placing.place(machine, remote, self.core.plan):
            self.core.states[item_id] = ELSEWHERE

    def mirror(self, event: Event, state: str | None = None) -> None:
        """An event of a process another machine runs, as its share sent it, with the
        state it left it in: told to the consumers and triggers as a local one is."""
        core = self.core
        process_id = event.process
        if process_id is None or process_id not in core.states:
            return
        if isinstance(event, Output):
            core.emit(event)
            if core.triggers.watches_output:  # OnProcessIO handlers here
                self.actions.dispatch_io(process_id, event.stream or "stdout", event.lines,
                                         core.placing.pids_elsewhere.get(process_id, 0))
            return
        if isinstance(event, Started) and event.pid is not None:
            core.placing.pids_elsewhere[process_id] = event.pid
        if state is not None:
            core.states[process_id] = state
        if isinstance(event, ProcessExited) and event.code is not None:
            record = core.records[process_id]
            record.exit_code = event.code
            if event.crashed and not core.shutting_down:  # as its machine decided
                record.crash_code, record.crash_time = event.code, time.monotonic()
        core.emit(event)
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
        core = self.core
        if process_id not in {p.id for p in core.plan.processes}:
            raise LaunchError(f"no process {process_id!r} in this launch")
        self.actions.process_event(process_id, on, pid, code)
        core.flag(process_id, on).set()
        core.changed.set()
