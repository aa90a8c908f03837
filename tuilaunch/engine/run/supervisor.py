"""Run a Plan: start processes, read their output, fire triggers, respawn, shut down.

Each process leads its own process group (its own session); the supervisor signals the
group as one. A watchdog process stops every process of the launch if tuilaunch dies,
however it dies (run/watchdog.py). Every output line goes to the process's log file before
any consumer sees it; consumers only get events, and a consumer that fails (a closed stdout,
a dead terminal) never stops the reading of a pipe nor a shutdown.

No thread per child: each child's exit is watched through a pidfd on the event loop, and
its output through non-blocking reads on the same loop.
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import time
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ..describe.entities import Entity, LogInfo, Shutdown, entity_list
from ..describe.launch_events import EventInfo, event_for
from ..describe.substitutions import PerformContext, perform
from ..plan.model import ActionPlan, Plan, PlanDiff, ProcessPlan, Trigger, diff_plans
from ..plan.params import write_parameter_file
from .events import Consumer, Event, LaunchEvent
from .logfiles import LogFile
from .plugins import ActionRunner, SupervisorPlugin
from .readers import ChannelReader, Running
from .spawn import spawn
from .watchdog import Watchdog

EOF_GRACE = 1.0
"""Seconds to wait, once a process is reaped, for the end of its output. A daemonised
grandchild may hold the pipe for ever: its exit is then reported anyway, and whatever it
still prints is read and logged until the launch ends."""

_STAGES = (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)
_STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
STOP_RACE = 2.0
"""Seconds before a stop within which a child's death by that stop's signal counts as part
of the stop (see Supervisor._real_crashes)."""


class Supervisor:
    def __init__(self, plan: Plan, log_dir: Path, sigterm_timeout: float = 5.0,
                 sigkill_timeout: float = 5.0,
                 plugins: Iterable[SupervisorPlugin] = ()) -> None:
        """`plugins` (run/plugins.py) add what `run` does not know: ROS actions, lifecycle
        nodes, components. engine/launcher.py makes a supervisor with the ROS ones."""
        self.plan = plan
        self.plugins: list[SupervisorPlugin] = []
        self._action_runners: dict[str, ActionRunner] = {}
        self._detached_actions: set[str] = set()
        self.log_dir = log_dir
        self.sigterm_timeout = sigterm_timeout
        self.sigkill_timeout = sigkill_timeout
        self.consumers: list[Consumer] = []
        self.states: dict[str, str] = {
            p.id: ("pending" if p.enabled else "skipped") for p in plan.processes}
        self.states.update({a.id: ("pending" if a.enabled else "skipped") for a in plan.actions})
        self._io_watchers: dict[tuple[str, str], list[ActionPlan]] = {}
        self._on_shutdown: list[ActionPlan] = []
        self._any_watchers: dict[str, list[ActionPlan]] = {}  # handlers without a target
        self._last_event: dict[tuple[str, str], EventInfo] = {}
        self._shutdown_requested = False
        self.exit_codes: dict[str, int] = {}
        self.crashes: dict[str, int] = {}
        """Processes that exited on their own with a non-zero status (not stopped by us)."""
        self._crash_times: dict[str, float] = {}
        self._stop_time: float | None = None
        self._running: dict[str, Running] = {}
        self._lingering: set[ChannelReader] = set()  # output still open after its process exited
        self._happened: dict[tuple[str, str], asyncio.Event] = {}
        # lifecycle transitions seen per (node or "*", state filter), and an event pulsed at
        # each: what re-runs the actions of an OnStateTransition on every match
        self._occurrences: dict[tuple[str, str], int] = {}
        self._pulses: dict[tuple[str, str], asyncio.Event] = {}
        self._busy = 0  # triggers sleeping or respawns scheduled
        self._tasks: set[asyncio.Task[Any]] = set()
        self._shutting_down = False
        self._urgency = 0  # 0: SIGINT first; 1: SIGTERM now; 2: SIGKILL now
        self._hurry: asyncio.Event | None = None
        self._changed = asyncio.Event()
        self._retries: dict[str, int] = {}
        self._quick_failures: dict[str, int] = {}  # crashes in a row within 2 s of starting
        self._keep_alive = False
        self._reported: set[str] = set()
        self._env_cache: dict[str, str] | None = None
        self.watchdog = Watchdog()
        for plugin in plugins:
            self.add_plugin(plugin)
        log_dir.mkdir(parents=True, exist_ok=True)
        self._launch_log = LogFile(log_dir / "launch.log", self._report_io)

    # --- events ----------------------------------------------------------------------

    def add_plugin(self, plugin: SupervisorPlugin) -> None:
        """Plugs in before `run`: its action kinds join those the supervisor performs."""
        self.plugins.append(plugin)
        self._action_runners.update(plugin.actions())
        self._detached_actions.update(plugin.detached_actions)

    @property
    def shutting_down(self) -> bool:
        """The launch is stopping: nothing new starts, waits should give up."""
        return self._shutting_down

    def subscribe(self, consumer: Consumer) -> None:
        self.consumers.append(consumer)

    def emit(self, event: Event) -> None:
        """Tells every consumer; one that raises is reported once and never stops us."""
        if event.kind != "output":
            detail = " ".join(f"{k}={v}" for k, v in (("pid", event.pid), ("code", event.code),
                                                       ("reason", event.reason)) if v is not None)
            self._launch_log.write(f"{event.time:.3f} {event.kind} {event.process or ''} "
                                   f"{detail}\n".encode())
        for consumer in list(self.consumers):
            try:
                consumer(event)
            except Exception as exc:
                self._consumer_failed(consumer, exc)
        self._changed.set()

    def log(self, text: str, level: str = "INFO") -> None:
        """A line for the launch pane and launch.log from whoever runs the supervisor."""
        self.emit(Event("log", None, reason=text, level=level))

    def _consumer_failed(self, consumer: Consumer, exc: Exception) -> None:
        name = getattr(consumer, "__qualname__", type(consumer).__name__)
        text = f"{name} failed on an event: {type(exc).__name__}: {exc}"
        if text in self._reported:
            return
        self._reported.add(text)
        self._launch_log.write(f"{time.time():.3f} error  reason={text}\n".encode())
        _to_stderr(f"tuilaunch: {text}; the launch goes on")

    def _report_io(self, text: str) -> None:
        """A log file that cannot be written: said to the consumers (on stderr without)."""
        if not self.consumers:
            _to_stderr(f"tuilaunch: {text}")
        event = Event("log", None, reason=text, level="ERROR")
        for consumer in list(self.consumers):
            try:
                consumer(event)
            except Exception as exc:
                self._consumer_failed(consumer, exc)

    def _flag(self, process_id: str, what: str) -> asyncio.Event:
        return self._happened.setdefault((process_id, what), asyncio.Event())

    def state_reached(self, process_id: str, what: str) -> None:
        """A lifecycle transition matching `what`: once for start-up chains, and counted
        for the handlers that run on each match."""
        key = (process_id, what)
        self._flag(process_id, what).set()
        self._occurrences[key] = self._occurrences.get(key, 0) + 1
        pulse = self._pulses.pop(key, None)
        if pulse is not None:
            pulse.set()

    async def _on_every_state(self, action: ActionPlan) -> None:
        """launch_ros's OnStateTransition: the entities run on the first matching
        transition and again on each later one (a node cycled by the operator or a
        manager), until shutdown."""
        trigger = action.trigger
        assert trigger is not None and trigger.target is not None
        key = (trigger.target, _flag_name(trigger))
        await self._when_ready(trigger, self._run_action, action)
        seen = self._occurrences.get(key, 0)
        while not self._shutting_down:
            while self._occurrences.get(key, 0) <= seen:
                await self._pulses.setdefault(key, asyncio.Event()).wait()
            seen += 1
            if self._shutting_down or not action.enabled:
                return
            if trigger.delay:
                await asyncio.sleep(trigger.delay)
            await self._run_action(action)

    # --- running ---------------------------------------------------------------------

    async def run(self, keep_alive: bool = False) -> int:
        """Runs until nothing can happen any more, or shutdown; returns an exit status.

        0 when every process ended well or was stopped on request (whatever signal it died
        of); 1 when a process could not start or exited on its own with a failure.

        With keep_alive (an interactive UI), only shutdown ends the run: an operator who
        stops every process still wants to start them again."""
        self._keep_alive = keep_alive
        try:
            for proc in self.plan.processes:
                if proc.enabled and proc.trigger is None:
                    self._start_now(proc.id)  # no task per process: start-up at the floor
                elif proc.enabled:
                    self._spawn_task(self._when_ready(proc.trigger, self.start, proc.id))
            for action in self.plan.actions:
                if action.enabled:
                    self._schedule_action(action)
            while not self._settled():
                self._changed.clear()
                await self._changed.wait()
            if not self._shutting_down and self._on_shutdown:
                # as launch does when nothing is left to run: OnShutdown handlers see it
                await self.shutdown("idle")
                while not self._settled():
                    self._changed.clear()
                    await self._changed.wait()
        finally:
            await self._finish()
        failed = [item for item, state in self.states.items() if state == "failed"]
        return 1 if failed or self._real_crashes() else 0

    def _real_crashes(self) -> dict[str, int]:
        """Crashes, less the processes that died of the stop signal itself just before the
        stop was seen: a terminal's Ctrl+C or hang-up reaches a child that is still in
        tuilaunch's process group for the instant between its fork and its own session."""
        if self._stop_time is None:
            return self.crashes
        return {pid: code for pid, code in self.crashes.items()
                if not (-code in _STOP_SIGNALS and
                        self._stop_time - self._crash_times[pid] < STOP_RACE)}

    async def _finish(self) -> None:
        """Whatever ended the run: nothing left running, nothing left open."""
        if self._running:  # cancelled from outside: stop what still runs, quickly
            self._shutting_down = True
            self._urgency = max(self._urgency, 1)
            await asyncio.gather(*(self._escalate(r) for r in list(self._running.values())),
                                 return_exceptions=True)
        await self._drain()
        for reader in list(self._lingering):
            reader.close()
        for plugin in self.plugins:
            try:
                await plugin.close()
            except Exception as exc:  # a plugin that fails to close never stops the end
                self._report_io(f"{type(plugin).__name__} failed to close: "
                                f"{type(exc).__name__}: {exc}")
        self._launch_log.close()
        self._remove_parameter_files()
        # the watchdog stops what a node left behind (daemons, stray group members)
        self.watchdog.close()
        deadline = time.monotonic() + self.watchdog.grace + 3.0
        while not self.watchdog.finished() and time.monotonic() < deadline:
            await asyncio.sleep(0.02)

    def _spawn_task(self, coro: Any) -> None:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._task_done)

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        self._tasks.discard(task)
        if not task.cancelled() and task.exception() is not None:
            exc = task.exception()
            self._report_io(f"internal error: {type(exc).__name__}: {exc}")
            self._changed.set()

    def _settled(self) -> bool:
        if self._shutting_down:
            # waiting actions, timers and respawns are cancelled when the run drains;
            # exit handlers of the processes being stopped still run, as in launch
            return not self._running and not self._actions_due_in_shutdown()
        if self._keep_alive or self._running or self._busy or self._shutdown_requested:
            return False
        if any(state == "running" for state in self.states.values()):
            return False  # an action is waiting for its service or node
        # a pending item can still start only if what it waits for is alive or pending
        waiting = [p.trigger for p in self.plan.processes if self.states[p.id] == "pending"]
        return not any(self._can_fire(trigger) for trigger in waiting) and not any(
            self._action_can_fire(a) for a in self.plan.actions
            if self.states.get(a.id) == "pending")

    def _can_fire(self, trigger: Trigger | None) -> bool:
        while trigger is not None:
            if trigger.target == "*" and trigger.on == "state":
                # any lifecycle node of the launch: one of them must still be able to run
                if not self._flag("*", _flag_name(trigger)).is_set() and not any(
                        p.lifecycle and self.states.get(p.id) in ("running", "pending")
                        for p in self.plan.processes):
                    return False
            if trigger.target not in (None, "*") and trigger.on in ("start", "exit", "state"):
                assert trigger.target is not None
                done = self._flag(trigger.target, _flag_name(trigger)).is_set()
                if not done and self.states.get(trigger.target) not in ("running", "pending"):
                    return False
            trigger = trigger.after
        return True

    async def _when_ready(self, trigger: Trigger | None, then: Callable[[Any], Any],
                          item: Any) -> None:
        chain: list[Trigger] = []
        while trigger is not None:
            chain.insert(0, trigger)
            trigger = trigger.after
        for step in chain:
            if step.on == "shutdown" or step.on == "io":
                return  # run by their own events, not as a start-up chain
            if step.target is not None:
                await self._flag(step.target, _flag_name(step)).wait()
            if step.delay:
                self._busy += 1
                try:
                    await asyncio.sleep(step.delay)
                finally:
                    self._busy -= 1
                    self._changed.set()
            if self._shutting_down and not _runs_in_shutdown(step, item):
                return
        result = then(item)
        if asyncio.iscoroutine(result):
            await result

    # --- actions ---------------------------------------------------------------------------

    def _schedule_action(self, action: ActionPlan) -> None:
        chain = action.trigger
        while chain is not None and chain.on not in ("io", "shutdown"):
            chain = chain.after
        first = action.trigger
        if chain is not None and chain.on == "shutdown":
            self._on_shutdown.append(action)
        elif first is not None and first.target is None and first.on in ("start", "exit", "io"):
            # a handler without target_action: every process's event runs it
            kind = f"io:{first.io or 'stdout'}" if first.on == "io" else first.on
            self._any_watchers.setdefault(kind, []).append(action)
        elif chain is not None and chain.target is not None:
            key = (chain.target, chain.io or "stdout")
            self._io_watchers.setdefault(key, []).append(action)
        elif first is not None and first.on == "state" and first.repeat and \
                first.target is not None:
            self._spawn_task(self._on_every_state(action))
        else:
            self._spawn_task(self._when_ready(action.trigger, self._run_action, action))

    def _action_can_fire(self, action: ActionPlan) -> bool:
        """Whether a pending action may still run before the launch goes idle."""
        trigger = action.trigger
        if trigger is not None and trigger.target is None and trigger.on in ("start", "exit",
                                                                              "io"):
            return False  # runs per event; it never holds the launch open by itself
        chain = trigger
        while chain is not None:
            if chain.on == "shutdown":
                return False
            if chain.on == "io" and chain.target is not None and \
                    self.states.get(chain.target) not in ("running", "pending"):
                return False
            chain = chain.after
        return self._can_fire(trigger)

    def _actions_due_in_shutdown(self) -> bool:
        """Exit handlers whose process has just stopped, or that are still running."""
        for action in self.plan.actions:
            state = self.states.get(action.id)
            if state == "running" and action.kind not in self._detached_actions:
                return True
            if state == "pending" and action.enabled and action.trigger is None:
                return True  # performed by a handler just now, about to run
            if state == "pending" and action.enabled and action.trigger is not None:
                step: Trigger | None = action.trigger
                due = True
                while step is not None and due:
                    due = (step.on == "exit" and not step.delay and step.target is not None
                           and self._flag(step.target, "exit").is_set())
                    step = step.after
                if due:
                    return True
        return False

    def _process_event(self, process_id: str, on: str, pid: int | None = None,
                       returncode: int | None = None) -> None:
        """A process started or exited: remember the event and run handlers without target."""
        proc = self.plan.process(process_id)
        event = event_for(on, process_name=process_id, pid=pid, returncode=returncode,
                          action=proc.source, cmd=proc.cmd)
        self._last_event[(process_id, on)] = event
        for action in self._any_watchers.get(on, []):
            self.states[action.id] = "running"  # due now: the run must not end before it
            self._spawn_task(self._run_action(action, event))

    def add_to_plan(self, processes: list[ProcessPlan], actions: list[ActionPlan],
                    event: EventInfo | None = None) -> None:
        """Processes and actions performed at event time join the run."""
        for proc in processes:
            self.states[proc.id] = "pending" if proc.enabled else "skipped"
            if proc.enabled and not self._shutting_down:  # launch starts nothing in shutdown
                self._spawn_task(self._when_ready(proc.trigger, self.start, proc.id))
        for action in actions:
            self.states[action.id] = "pending" if action.enabled else "skipped"
            if event is not None:
                self._last_event[(action.id, "made")] = event
            if action.enabled:
                self._schedule_action(action)
        self._changed.set()

    def _perform_at_event(self, action: ActionPlan, entities: list[Any],
                          event: EventInfo) -> bool:
        from ..errors import LaunchError
        from .event_actions import perform_entities

        try:
            performed = perform_entities(self.plan, action, entities, event)
        except LaunchError as exc:  # only this handler fails, as in launch
            self._log(action, str(exc).replace("\n", " "), "ERROR")
            return False
        for warning in performed.warnings:
            self._log(action, warning, "WARN")
        self.add_to_plan(performed.processes, performed.actions, event)
        return True

    def _event_of(self, action: ActionPlan) -> EventInfo:
        """The event an action was triggered by (its process's start or exit, ...)."""
        if (action.id, "made") in self._last_event:  # performed by an event handler
            return self._last_event[(action.id, "made")]
        step = action.trigger
        while step is not None:
            if step.target is not None and (step.target, step.on) in self._last_event:
                return self._last_event[(step.target, step.on)]
            step = step.after
        on = action.trigger.on if action.trigger is not None else "timer"
        return event_for(on)

    async def _run_action(self, action: ActionPlan, event: EventInfo | None = None) -> None:
        if event is None:
            event = self._event_of(action)
        self.states[action.id] = "running"
        self.emit(Event("started", action.id))
        self._flag(action.id, "start").set()
        ok = True
        try:
            runner = self._action_runners.get(action.kind)
            if runner is not None:
                ok = await runner(action)
            elif action.kind == "shutdown":
                self._request_shutdown(str(action.data))
            elif action.kind == "log":
                self._log(action, self._perform(action, action.source.msg, event))
            elif action.kind == "event_callback":
                ok = self._run_callbacks(action, event or LaunchEvent())
            elif action.kind == "deferred":
                from .event_actions import deferred_entities

                ok = self._perform_at_event(action, deferred_entities(action), event)
            elif action.kind == "stop_process":
                ok = await self._stop_process(action)
            else:
                self._log(action, f"{action.kind} is not supported yet; skipped", "WARN")
        except asyncio.CancelledError:
            self.states[action.id] = "cancelled"
            raise
        self.states[action.id] = "done" if ok else "failed"
        self.emit(Event("finished", action.id, reason=self.states[action.id]))
        self._flag(action.id, "exit").set()

    def _request_shutdown(self, reason: str) -> None:
        """A Shutdown action: the run must not end before the shutdown has begun."""
        self._shutdown_requested = True
        self._spawn_task(self.shutdown(reason))

    async def _stop_process(self, action: ActionPlan) -> bool:
        """EmitEvent(ShutdownProcess(process_matcher=matches_action(x)))."""
        target = str(action.target)
        if target not in self.states:
            self._log(action, f"cannot stop {target}: this launch does not run it", "WARN")
            return False
        self._spawn_task(self.stop(target))
        return True

    def _log(self, action: ActionPlan, text: str, level: str = "INFO") -> None:
        self.emit(Event("log", action.id, reason=text, level=level))

    def _perform(self, action: ActionPlan, value: Any, event: LaunchEvent | None) -> str:
        context = PerformContext(action.configurations, None,
                                 event_locals={"event": event or LaunchEvent()})
        return perform(value, context)

    def _run_callbacks(self, action: ActionPlan, event: LaunchEvent) -> bool:
        """Launch-file functions called with the event; what they return is carried out."""
        source = action.source
        launcher = getattr(source, "launcher", None)
        produced: list[Any] = []
        try:
            for callback in source.callbacks:
                if launcher is not None:
                    with launcher.capture() as added:
                        produced += entity_list(callback(event)) + added
                else:
                    produced += entity_list(_call_handler(callback, event, action))
        except Exception as exc:  # a user's callback must never stop the launch
            self._log(action, f"event callback ({action.origin}) raised "
                      f"{type(exc).__name__}: {exc}", "ERROR")
            return False
        seen: set[int] = set()
        rest: list[Any] = []
        for entity in produced:
            if id(entity) in seen:
                continue
            seen.add(id(entity))
            if not self._carry_out(action, entity, event):
                rest.append(entity)
        return self._perform_at_event(action, rest, event) if rest else True

    def _carry_out(self, action: ActionPlan, entity: Entity, event: EventInfo) -> bool:
        """Log lines and shutdown at once; False for what must be resolved into the plan."""
        if isinstance(entity, LogInfo):
            self._log(action, self._perform(action, entity.msg, event))
        elif isinstance(entity, Shutdown):
            self._request_shutdown(self._perform(action, entity.reason, event))
        else:
            return False
        return True

    def _deliver_lines(self, running: Running, stream: str, lines: list[str]) -> None:
        """A block of a process's output, already in its log file: to the consumers."""
        self.emit(Event("output", running.plan.id, stream=stream, lines=lines))
        if self._io_watchers or self._any_watchers:
            self._dispatch_io(running.plan.id, stream, lines, running.process.pid)

    def _dispatch_io(self, process_id: str, stream: str, lines: list[str], pid: int) -> None:
        watchers = [*self._io_watchers.get((process_id, stream), []),
                    *self._any_watchers.get(f"io:{stream}", [])]
        source = self.plan.process(process_id).source if watchers else None
        for action in watchers:
            for line in lines:
                event = event_for("io", stream, process_name=process_id, pid=pid,
                                  text=(line + "\n").encode(), action=source)
                self._spawn_task(self._run_action(action, event))

    async def start(self, process_id: str) -> None:
        """Starts one process (also a stopped or exited one, from the UI)."""
        self._start_now(process_id)

    def _start_now(self, process_id: str) -> None:
        """From the check that the launch is not shutting down to the registration of the
        child nothing awaits, so a shutdown either prevents the start or sees the child."""
        proc = self.plan.process(process_id)
        if process_id in self._running or self._shutting_down:
            return
        if proc.error:
            where = f" ({proc.origin})" if proc.origin else ""
            self._fail(process_id, proc.error + where)
            return
        try:
            for path, values in proc.generated_parameter_files:
                write_parameter_file(Path(path), values)
        except Exception as exc:  # a LaunchError or an OSError: either way, one line
            self._fail(process_id, f"cannot write its parameter file: {exc}")
            return
        env = {} if proc.clear_env else dict(self._base_env())
        env.update(proc.env)
        env.setdefault("PYTHONUNBUFFERED", "1")
        env.setdefault("RCUTILS_LOGGING_BUFFERED_STREAM", "1")
        env.setdefault("RCUTILS_COLORIZED_OUTPUT", "0" if os.environ.get("NO_COLOR") else "1")
        self.watchdog.start()
        if self.watchdog.error and "watchdog" not in self._reported:
            self._reported.add("watchdog")
            self._report_io(f"{self.watchdog.error}: processes may outlive a crash of "
                            "tuilaunch")
        self.watchdog.mark(env)
        log_path = self.log_dir / f"{process_id}.log"
        try:
            log = LogFile(log_path, self._report_io)
        except OSError as exc:
            self._fail(process_id, f"cannot open its log file {log_path}: "
                       f"{exc.strerror or exc}")
            return
        try:
            child = spawn(proc.cmd, env, proc.cwd, _wants_tty(proc))
        except Exception as exc:  # OSError, or ValueError for a NUL byte in an argument
            log.close()
            what = getattr(exc, "filename", None)
            what = what if isinstance(what, str) else proc.cmd[0]
            self._fail(process_id, f"cannot start {what}: "
                       f"{getattr(exc, 'strerror', None) or exc}")
            return
        popen = child.popen
        loop = asyncio.get_running_loop()
        running = None
        try:
            self.watchdog.watch(popen.pid)
            running = Running(proc, popen, log, time.monotonic(), loop.create_future())
            self._running[process_id] = running
            self._watch_exit(running)
            for channel in child.channels:
                running.readers.append(ChannelReader(running, channel, self._deliver_lines))
        except Exception as exc:
            # nothing may run that nobody reads or stops
            _kill_group(popen.pid, signal.SIGKILL)
            popen.wait()
            if running is not None and running.pidfd is not None:
                loop.remove_reader(running.pidfd)
                _close_quietly(running.pidfd)
            for channel in child.channels:
                loop.remove_reader(channel.fd)
                _close_quietly(channel.fd)
            log.close()
            self._running.pop(process_id, None)
            self._fail(process_id, f"could not be tracked and was killed: "
                       f"{type(exc).__name__}: {exc}")
            return
        self.states[process_id] = "running"
        self.emit(Event("started", process_id, pid=popen.pid))
        self._process_event(process_id, "start", popen.pid)
        self._flag(process_id, "start").set()
        for plugin in self.plugins:
            follow_up = plugin.process_started(proc)
            if follow_up is not None:
                self._spawn_task(follow_up)
        self._spawn_task(self._wait(running))

    def _base_env(self) -> dict[str, str]:
        """tuilaunch's environment as it was at the first start: read once, not per child."""
        if self._env_cache is None:
            self._env_cache = dict(os.environ)
        return self._env_cache

    def _fail(self, process_id: str, reason: str) -> None:
        self.states[process_id] = "failed"
        self.emit(Event("failed", process_id, reason=reason))

    def _watch_exit(self, running: Running) -> None:
        """The child's exit wakes the loop through a pidfd: no thread per child."""
        loop = asyncio.get_running_loop()
        try:
            running.pidfd = os.pidfd_open(running.process.pid)
        except (OSError, AttributeError):
            running.pidfd = None  # old kernel, or no descriptor left: poll instead
            loop.call_later(0.05, self._poll_exit, running)
            return
        loop.add_reader(running.pidfd, self._reap, running)

    def _poll_exit(self, running: Running) -> None:
        if running.process.poll() is not None:
            self._reap(running)
        else:
            asyncio.get_running_loop().call_later(0.05, self._poll_exit, running)

    def _reap(self, running: Running) -> None:
        if running.pidfd is not None:
            asyncio.get_running_loop().remove_reader(running.pidfd)
            os.close(running.pidfd)
            running.pidfd = None
        code = running.process.wait()  # a zombie by now: does not block
        if not running.exited.done():
            running.exited.set_result(code)

    async def _wait(self, running: Running) -> None:
        code = await running.exited
        running.reaped = True
        pending = [r.done for r in running.readers if not r.done.done()]
        if pending:
            await asyncio.wait(pending, timeout=EOF_GRACE)
        lingering = [r for r in running.readers if not r.done.done()]
        self._lingering.update(lingering)
        for reader in lingering:
            reader.done.add_done_callback(self._forget_reader(reader))
        if not lingering:
            running.log.close()
        if not _group_alive(running.process.pid):
            self.watchdog.forget(running.process.pid)
        process_id = running.plan.id
        del self._running[process_id]
        self.exit_codes[process_id] = code
        requested = running.stopping or self._shutting_down
        if code != 0 and not requested:
            self.crashes[process_id] = code
            self._crash_times[process_id] = time.monotonic()
        self.states[process_id] = "exited"
        for plugin in self.plugins:
            plugin.process_exited(process_id)
        # `requested`: a stop asked by anyone (another client, `tuilaunch stop`), not a crash
        self.emit(Event("exited", process_id, pid=running.process.pid, code=code,
                         reason=_describe_exit(code), data={"requested": requested}))
        self._process_event(process_id, "exit", running.process.pid, code)
        self._flag(process_id, "exit").set()
        if self._should_respawn(running, code):
            await self._respawn(running)
        elif running.plan.respawn and code != 0 and not requested:
            tries = self._retries.get(process_id, 0)
            self.emit(Event("log", process_id, level="ERROR", reason=(
                f"respawn gives up: it failed {tries + 1} times "
                f"(respawn_max_retries={running.plan.respawn_max_retries})")))

    def _forget_reader(self, reader: ChannelReader) -> Callable[[asyncio.Future[None]], None]:
        return lambda _: self._lingering.discard(reader)

    def _should_respawn(self, running: Running, code: int) -> bool:
        proc = running.plan
        if not proc.respawn or running.stopping or self._shutting_down or code == 0:
            return False  # a clean exit is a finished job, not a crash
        limit = proc.respawn_max_retries
        return limit < 0 or self._retries.get(proc.id, 0) < limit

    async def _respawn(self, running: Running) -> None:
        proc = running.plan
        tries = self._retries[proc.id] = self._retries.get(proc.id, 0) + 1
        # back off while it dies at once, so a crash loop does not spin the machine; a run
        # that lasted starts the count again (a driver that fails once an hour for days
        # comes back after its own delay, not after the cap)
        quick = time.monotonic() - running.started < 2.0
        streak = self._quick_failures[proc.id] = (
            self._quick_failures.get(proc.id, 0) + 1 if quick else 0)
        delay = min(max(proc.respawn_delay, 0.1) * 2 ** min(max(streak - 1, 0), 16), 30.0)
        delay = max(delay, proc.respawn_delay)
        self.states[proc.id] = "respawning"
        self._busy += 1
        self.emit(Event("respawning", proc.id, reason=f"try {tries} in {delay:g} s"))
        try:
            await asyncio.sleep(delay)
        finally:
            self._busy -= 1
        if not self._shutting_down:
            await self.start(proc.id)

    # --- stopping -------------------------------------------------------------------------

    async def stop(self, process_id: str) -> None:
        running = self._running.get(process_id)
        if running is not None:
            running.stopping = True
            await self._escalate(running)

    async def replace_plan(self, plan: Plan) -> PlanDiff:
        """Relaunch with new argument values: stop what changed, start what is new.

        Processes whose command, environment and parameters are unchanged are left as they
        are (running, finished or waiting for their trigger); triggers of new processes fire
        at once when what they wait for already happened.
        """
        running = {pid for pid in self._running}
        diff = diff_plans(self.plan, plan, running)
        self._busy += 1
        try:
            await asyncio.gather(*(self.stop(pid) for pid in diff.stop if pid in running))
            old_actions = {(a.kind, a.target, repr(a.data)) for a in self.plan.actions
                           if a.enabled}
            self.plan = plan
            for proc in plan.processes:
                # a kept process keeps its state: finished, failed, or still waiting
                if proc.id not in self._running and proc.id not in diff.keep:
                    self.states[proc.id] = "pending" if proc.enabled else "skipped"
            self._io_watchers.clear()
            self._on_shutdown.clear()
            self._any_watchers.clear()
            for proc in plan.processes:
                if proc.id in diff.start:
                    self._spawn_task(self._when_ready(proc.trigger, self.start, proc.id))
            for action in plan.actions:
                self.states.setdefault(action.id, "pending" if action.enabled else "skipped")
                fresh = (action.kind, action.target, repr(action.data)) not in old_actions
                on_event = action.trigger is not None and action.trigger.on in ("io", "shutdown")
                # event watchers were cleared above and come back; one-off actions rerun
                # only when they are new or their target or data changed
                if action.enabled and (fresh or on_event):
                    self._schedule_action(action)
        finally:
            self._busy -= 1
            self._changed.set()
        return diff

    async def restart(self, process_id: str) -> None:
        self._busy += 1  # the run must not look finished between the stop and the start
        try:
            await self.stop(process_id)
            await self.start(process_id)
        finally:
            self._busy -= 1
            self._changed.set()

    async def run_action(self, action_id: str) -> None:
        """Performs one action of the plan again (the UI restarted its group)."""
        action = next((a for a in self.plan.actions if a.id == action_id), None)
        if action is None or not action.enabled or self._shutting_down:
            return
        self._busy += 1
        try:
            await self._run_action(action)
        finally:
            self._busy -= 1
            self._changed.set()

    async def shutdown(self, reason: str = "shutdown") -> None:
        if self._shutting_down:
            return
        self._shutting_down = True
        self._stop_time = time.monotonic()
        try:
            self.emit(Event("shutdown", reason=reason))
            for action in self._on_shutdown:
                try:
                    await self._run_action(action, LaunchEvent(reason=reason))
                except Exception as exc:  # an OnShutdown action never stops the shutdown
                    self._report_io(f"on-shutdown action {action.id} raised "
                                    f"{type(exc).__name__}: {exc}")
        finally:
            await asyncio.gather(*(self._escalate(r) for r in list(self._running.values())),
                                 return_exceptions=True)
            self._changed.set()

    def escalate_now(self) -> str | None:
        """The operator insists (a second Ctrl+C): SIGTERM now; once more: SIGKILL.

        Returns the signal's name now sent, or None when nothing is left to stop."""
        if not self._running:
            return None
        self._urgency = min(self._urgency + 1, len(_STAGES) - 1)
        if self._hurry is not None:
            self._hurry.set()
        self._hurry = None
        if not self._shutting_down:
            self._spawn_task(self.shutdown("stop requested again"))
        return _STAGES[self._urgency].name

    async def _escalate(self, running: Running) -> None:
        """SIGINT, then SIGTERM, then SIGKILL, to the whole process group.

        The waits are the process's own sigterm_timeout / sigkill_timeout when it sets them;
        each step is announced; `escalate_now` skips the wait."""
        running.stopping = True
        proc = running.plan
        waits = (proc.sigterm_timeout if proc.sigterm_timeout is not None
                 else self.sigterm_timeout,
                 proc.sigkill_timeout if proc.sigkill_timeout is not None
                 else self.sigkill_timeout, 10.0)
        sent = -1
        stage = 0
        why = ""
        while not running.exited.done():
            stage = max(stage, self._urgency if self._shutting_down else 0)
            if stage > sent:
                if stage > 0:
                    self.emit(Event("log", proc.id, level="WARN", reason=(
                        f"{why}sending {_STAGES[stage].name} to its process group")))
                if not _kill_group(running.process.pid, _STAGES[stage]):
                    break  # the whole group is gone; the exit arrives through the pidfd
                sent = stage
            if self._hurry is None:
                self._hurry = asyncio.Event()
            hurry: asyncio.Future[Any] = asyncio.ensure_future(self._hurry.wait())
            exited: asyncio.Future[Any] = running.exited
            try:
                await asyncio.wait([exited, hurry], timeout=waits[stage],
                                   return_when=asyncio.FIRST_COMPLETED)
            finally:
                hurry.cancel()
            if running.exited.done():
                break
            if stage == len(_STAGES) - 1:
                self.emit(Event("log", proc.id, level="ERROR", reason=(
                    f"still there {waits[stage]:g} s after SIGKILL (stuck in the kernel?); "
                    "no longer waiting for it")))
                return
            if self._urgency > stage and self._shutting_down:
                why = "asked again: "
            else:
                why = f"still running {waits[stage]:g} s after {_STAGES[stage].name}: "
                stage += 1
        await asyncio.shield(running.exited)

    def kill_all(self) -> None:
        """Last resort when the caller cannot wait (the UI is being torn down): SIGKILL,
        and the watchdog sweeps what the processes left behind."""
        self._shutting_down = True
        for running in list(self._running.values()):
            _kill_group(running.process.pid, signal.SIGKILL)
        self._remove_parameter_files()
        self.watchdog.close()

    async def _drain(self) -> None:
        for task in list(self._tasks):
            if not task.done():
                task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)

    def _remove_parameter_files(self) -> None:
        for proc in self.plan.processes:
            for path, _ in proc.generated_parameter_files:
                Path(path).unlink(missing_ok=True)
        try:
            self.plan.params_dir.rmdir()
        except OSError:
            pass


def _wants_tty(proc: ProcessPlan) -> bool:
    """emulate_tty when the file says; else a terminal for every process whose output is
    shown, so C/C++ programs print line by line instead of in bursts at exit."""
    explicit = getattr(proc, "emulate_tty", None)
    if explicit is not None:
        return bool(explicit)
    return getattr(proc, "output", "screen") in ("screen", "both")


def _kill_group(pgid: int, sig: signal.Signals) -> bool:
    try:
        os.killpg(pgid, sig)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # a member changed user (sudo in a wrapper): the others got it
    return True


def _group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _close_quietly(fd: int) -> None:
    try:
        os.close(fd)
    except OSError:
        pass


def _to_stderr(text: str) -> None:
    """A message for the operator; a dead terminal must not turn it into a failure."""
    try:
        sys.stderr.write(text + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass


def _runs_in_shutdown(step: Trigger, item: Any) -> bool:
    """Exit handlers run while launch shuts down (their process stopped because of it)."""
    return isinstance(item, ActionPlan) and step.on == "exit" and not step.delay


def _call_handler(callback: Any, event: EventInfo, action: ActionPlan) -> Any:
    """Plain launch API handlers take (event, context); simple_launch's take (event)."""
    import inspect

    try:
        arity = len(inspect.signature(callback).parameters)
    except (TypeError, ValueError):
        arity = 1
    if arity >= 2:
        return callback(event, PerformContext(action.configurations,
                                              event_locals={"event": event}))
    return callback(event)


def _flag_name(trigger: Trigger) -> str:
    """A lifecycle state trigger waits for its own filter, other triggers for the event."""
    return f"state:{trigger.io}" if trigger.on == "state" else trigger.on


def _describe_exit(code: int) -> str:
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"
