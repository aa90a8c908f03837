"""Performing the plan's actions: log, shutdown, stop, event callbacks, plugins' kinds; and
waiting for their triggers (what has happened is in the TriggerBook, triggers.py).

Kinds a plugin registered (`call_service`, `lifecycle_transition`, ...) go to it; event
handlers' callbacks are called with the launch event, and what they return joins the run.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
from collections.abc import Awaitable, Callable
from typing import Any

from ...describe.entities import Entity, LogInfo, Shutdown, TriggerOn, entity_list
from ...describe.environ import captured_environ, shown_environ
from ...describe.python.launch_events import EventInfo, ProcessExited, event_for
from ...describe.substitutions import PerformContext, perform
from ...plan.model import ActionKind, ActionPlan, ProcessPlan, Trigger
from ..events import ActionFinished, LaunchEvent, Log, Started
from ..events import Shutdown as ShutdownEvent
from .core import SupervisorCore
from .triggers import flag_name, runs_in_shutdown

USER_LOGGER = "launch.user"  # the logger launch's LogInfo writes with

STARTED_AS_NODES = frozenset({ActionKind.CALL_SERVICE, ActionKind.SET_PARAMETERS})
"""Actions simple_launch runs as nodes (`simple_launch/call_service`, `set_parameters`):
launch starts no process once shutdown has begun (ExecuteLocal.execute returns when
`context.is_shutdown`), so these are never performed then, while a LogInfo beside them is."""


class PlanActions:
    """Waiting for triggers, performing one action of the plan, and what event handlers add
    to the run.

    Some actions act on processes (a handler's new process starts, a StopProcess, a
    Shutdown): `start`, `stop` and `shutdown` are the supervisor's verbs, handed in, as the
    processes are another behaviour's (starting.py, ending.py)."""

    def __init__(self, core: SupervisorCore,
                 start: Callable[[str], Awaitable[None]],
                 stop: Callable[[str], Awaitable[None]],
                 shutdown: Callable[[str], Awaitable[None]]) -> None:
        self.core = core
        self._start = start
        self._stop = stop
        self._shutdown = shutdown

    def state_reached(self, process_id: str, what: str) -> None:
        """A lifecycle transition matching `what` (how a plugin, the lifecycle tracker,
        reports a state): once for start-up chains, and counted for the handlers that run
        on each match."""
        self.core.triggers.state_reached(process_id, what)

    async def _on_every_state(self, action: ActionPlan) -> None:
        """launch_ros's OnStateTransition: the entities run on the first matching
        transition and again on each later one (a node cycled by the operator or a
        manager), until shutdown."""
        core = self.core
        trigger = action.trigger
        assert trigger is not None and trigger.target is not None
        key = (trigger.target, flag_name(trigger))
        seen = 0

        async def first(action: ActionPlan) -> None:
            # counted before the entities run: a transition made while they still run (an
            # activate whose reply comes after the node cycled back) runs them again
            nonlocal seen
            seen = core.triggers.transitions(key)
            await self.perform_action(action)

        await self.when_ready(trigger, first, action)
        while not core.shutting_down:
            await core.triggers.next_transition(key, seen)
            seen += 1
            if core.shutting_down or not action.enabled:
                return
            if trigger.delay:
                await asyncio.sleep(trigger.delay)
            await self.perform_action(action)

    async def when_ready(self, trigger: Trigger | None, then: Callable[[Any], Any],
                         item: Any) -> None:
        core = self.core
        chain: list[Trigger] = []
        while trigger is not None:
            chain.insert(0, trigger)
            trigger = trigger.after
        for step in chain:
            if step.on == TriggerOn.SHUTDOWN or step.on == TriggerOn.IO:
                return  # run by their own events, not as a start-up chain
            if step.target is not None:
                await core.flag(step.target, flag_name(step)).wait()
            if step.delay:
                core.busy += 1
                try:
                    await asyncio.sleep(step.delay)
                finally:
                    core.busy -= 1
                    core.changed.set()
            if core.shutting_down and not runs_in_shutdown(step, item):
                return
        result = then(item)
        if asyncio.iscoroutine(result):
            await result

    def schedule_action(self, action: ActionPlan) -> None:
        core = self.core
        filing = core.triggers.file(action)
        if filing == "every_state":
            core.spawn_task(self._on_every_state(action))
        elif filing == "chain":
            core.spawn_task(self.when_ready(action.trigger, self.perform_action, action))

    def process_event(self, process_id: str, on: str, pid: int | None = None,
                      returncode: int | None = None) -> None:
        """A process started or exited: remember the event and run handlers without target."""
        core = self.core
        proc = core.plan.process(process_id)
        event = event_for(on, process_name=process_id, pid=pid, returncode=returncode,
                          action=proc.source, cmd=proc.cmd)
        core.last_event[(process_id, on)] = event
        for action in core.triggers.handlers_of(on):
            core.states[action.id] = "running"  # due now: the run must not end before it
            core.spawn_task(self.perform_action(action, event))

    def add_to_plan(self, processes: list[ProcessPlan], actions: list[ActionPlan],
                    event: EventInfo | None = None) -> None:
        """Processes and actions performed at event time join the run."""
        core = self.core
        for proc in processes:
            core.states[proc.id] = "pending" if proc.enabled else "skipped"
            if proc.enabled and not core.shutting_down:  # launch starts nothing in shutdown
                core.spawn_task(self.when_ready(proc.trigger, self._start, proc.id))
        for action in actions:
            core.states[action.id] = "pending" if action.enabled else "skipped"
            if event is not None:
                core.last_event[(action.id, "made")] = event
            if action.enabled:
                self.schedule_action(action)
        core.changed.set()

    def _perform_at_event(self, action: ActionPlan, entities: list[Any],
                          event: EventInfo) -> bool:
        core = self.core
        from ...errors import LaunchError
        from .event_actions import perform_entities

        try:
            performed = perform_entities(core.plan, action, entities, event)
        except LaunchError as exc:  # only this handler fails, as in launch
            core.log_action(action, str(exc).replace("\n", " "), "ERROR")
            return False
        for warning in performed.warnings:
            core.log_action(action, warning, "WARN")
        self.add_to_plan(performed.processes, performed.actions, event)
        return True

    def _event_of(self, action: ActionPlan) -> EventInfo:
        """The event an action was triggered by (its process's start or exit, ...)."""
        core = self.core
        if (action.id, "made") in core.last_event:  # performed by an event handler
            return core.last_event[(action.id, "made")]
        step = action.trigger
        while step is not None:
            if step.target is not None and (step.target, step.on) in core.last_event:
                return core.last_event[(step.target, step.on)]
            step = step.after
        on = action.trigger.on if action.trigger is not None else "timer"
        return event_for(on)

    def log_now(self, action: ActionPlan) -> None:
        """An untriggered LogInfo, said before any process starts: launch performs it
        while it visits the file, and a process's start is only said once the loop runs
        (`process started with pid` comes after every such line)."""
        self._action_begins(action)
        try:
            ok = self._log(action, self._event_of(action))
        except Exception as exc:  # as perform_action: this action fails alone
            self.core.log_action(action, failure_line(action, exc), "ERROR")
            ok = False
        self._action_ends(action, ok)

    def _action_begins(self, action: ActionPlan) -> None:
        core = self.core
        core.states[action.id] = "running"
        core.emit(Started(action.id))
        core.flag(action.id, "start").set()

    def _action_ends(self, action: ActionPlan, ok: bool) -> None:
        core = self.core
        core.states[action.id] = "done" if ok else "failed"
        core.emit(ActionFinished(action.id, reason=core.states[action.id]))
        core.flag(action.id, "exit").set()

    async def perform_action(self, action: ActionPlan, event: EventInfo | None = None) -> None:
        core = self.core
        if core.shutting_down and action.kind in STARTED_AS_NODES:
            # never started, as launch's node: no line, no exit event for what waits on it
            core.states[action.id] = "cancelled"
            core.emit(ActionFinished(action.id, reason="cancelled"))
            core.changed.set()
            return
        if event is None:
            event = self._event_of(action)
        self._action_begins(action)
        ok = True
        task = asyncio.current_task()
        if action.kind in core.detached_actions and task is not None:
            core.detached_tasks[action.id] = task
        try:
            runner = core.action_runners.get(action.kind)
            if runner is not None:
                ok = await runner(action)
            elif action.kind == ActionKind.SHUTDOWN:
                if isinstance(event, ProcessExited) and not getattr(action.source, "emitted",
                                                                     False):
                    # launch's Shutdown action says so (shutdown_action.py); an emitted
                    # Shutdown event, Ctrl+C, idle say nothing of a reason
                    core.log_action(action, f"process[{event.process_name}] was required: "
                                    "shutting down launched system", logger="launch")
                core.launch_reasons.add(str(action.data))
                if core.shutting_down and not _in_shutdown_handler(action):
                    await self.tell_shutdown(str(action.data))  # before the run may end
                else:
                    self._request_shutdown(str(action.data), action)
            elif action.kind == ActionKind.LOG:
                ok = self._log(action, event)
            elif action.kind == ActionKind.EVENT_CALLBACK:
                ok = self._run_callbacks(action, event or LaunchEvent())
            elif action.kind == ActionKind.DEFERRED:
                from .event_actions import deferred_entities

                ok = self._perform_at_event(action, deferred_entities(action), event)
            elif action.kind == ActionKind.STOP_PROCESS:
                ok = await self._stop_process(action)
            elif action.kind == ActionKind.SIGNAL_PROCESS:
                ok = self._signal_process(action)
            elif action.kind == ActionKind.COROUTINE:
                ok = await self._run_coroutine(action, event)
            else:
                core.log_action(action, f"{action.kind} is not supported yet; skipped", "WARN")
        except asyncio.CancelledError:
            if core.detached_tasks.get(action.id) is not task or not core.shutting_down:
                core.states[action.id] = "cancelled"
                raise
            # stopped by the shutdown (stop_detached_actions), as simple_launch's
            # call_service node is: it has finished, and its exit handlers run
        except Exception as exc:
            # Whatever an action raises (a substitution a handler's LogInfo cannot perform,
            # a plugin's bug), only this action fails, as in launch: left "running", the
            # run would wait for it forever and no signal could end the launch.
            core.log_action(action, failure_line(action, exc), "ERROR")
            ok = False
        finally:
            if core.detached_tasks.get(action.id) is task:
                del core.detached_tasks[action.id]
        self._action_ends(action, ok)

    def _log(self, action: ActionPlan, event: LaunchEvent | None) -> bool:
        from ...errors import LaunchError

        try:
            message = self._perform(action, action.source.msg, event)
        except LaunchError as exc:  # as launch: this action fails, the launch goes on
            where = f"{action.origin}: " if exc.origin is None and action.origin else ""
            self.core.log_action(action, where + str(exc).replace("\n", " "), "ERROR")
            return False
        self.core.log_action(action, message, logger=USER_LOGGER)
        return True

    def _request_shutdown(self, reason: str, action: ActionPlan) -> None:
        """A Shutdown action: the run must not end before the shutdown has begun. While
        the launch already stops (an exit handler of a process the first shutdown stopped),
        launch emits the event again and OnShutdown handlers see it, unless they asked."""
        core = self.core
        first = not (core.shutting_down or core.shutdown_requested)
        core.shutdown_requested = True
        if first:
            core.spawn_task(self._shutdown(reason))
        elif not _in_shutdown_handler(action):
            core.spawn_task(self.tell_shutdown(reason))

    async def tell_shutdown(self, reason: str) -> None:
        """The Shutdown event: said, and seen by the OnShutdown handlers. A Shutdown action
        performed while the launch already stops calls this again, as launch emits its
        event again (its handlers see both reasons)."""
        core = self.core
        core.emit(ShutdownEvent(reason=reason,
                                data={"launch": True} if reason in core.launch_reasons
                                else None))
        for action in core.triggers.on_shutdown:
            try:
                await self.perform_action(action, LaunchEvent(reason=reason))
            except Exception as exc:  # an OnShutdown action never stops the shutdown
                core.report_io(f"on-shutdown action {action.id} raised "
                               f"{type(exc).__name__}: {exc}")

    async def _stop_process(self, action: ActionPlan) -> bool:
        """EmitEvent(ShutdownProcess(process_matcher=matches_action(x)))."""
        target = self._target_of(action, "stop")
        if target is None:
            return False
        self.core.spawn_task(self._stop(target))
        return True

    def _target_of(self, action: ActionPlan, verb: str) -> str | None:
        """The process an emitted event is about, or None (said) when this launch does not
        run it."""
        target = str(action.target)
        if target not in self.core.states:
            self.core.log_action(action, f"cannot {verb} {target}: this launch does not run "
                                 "it", "WARN")
            return None
        return target

    def _signal_process(self, action: ActionPlan) -> bool:
        """EmitEvent(SignalProcess(signal_number=..., process_matcher=matches_action(x))):
        the signal to the process itself, not its group, in launch's words; one that is
        not running is left alone, as launch does."""
        core = self.core
        target, name = self._target_of(action, "signal"), str(action.data)
        if target is None:
            return False
        running = core.running.get(target)
        if running is None and core.states.get(target) == "running":
            core.log_action(action, f"cannot signal {target}: it runs on another machine",
                            "WARN")
            return False
        if running is None or running.reaped or running.exited.done():
            # launch: "not sent ... because it has closed already" (debug); a reaped pid
            # may be another process's by now
            return True
        core.emit(Log(target, reason=f"sending signal '{name}' to process[{target}]"))
        with contextlib.suppress(ProcessLookupError):
            os.kill(running.process.pid, getattr(signal, name))
        return True

    async def _run_coroutine(self, action: ActionPlan, event: LaunchEvent | None) -> bool:
        """OpaqueCoroutine: the file's async function on this loop until it returns. What it
        raises is this action's error with the line at fault; launch would end the whole
        launch, here the others go on (its OnExecutionComplete handlers still run, as the
        coroutine completed)."""
        from ...errors import origin_outside_tuilaunch

        source = action.source
        args = list(source.args)
        if not source.ignore_context:
            args.insert(0, self._context(action, event))
        try:
            await source.coroutine(*args, **source.kwargs)
        except Exception as exc:
            origin = origin_outside_tuilaunch(exc.__traceback__) or action.origin
            where = f" ({origin})" if origin else ""
            self.core.log_action(action, f"coroutine {source.name}{where} raised "
                                 f"{type(exc).__name__}: {exc}", "ERROR")
            return False
        return True

    def _perform(self, action: ActionPlan, value: Any, event: LaunchEvent | None) -> str:
        with shown_environ(self._environ_of(action)):
            return perform(value, self._context(action, event))

    def _context(self, action: ActionPlan, event: LaunchEvent | None) -> PerformContext:
        """The launch context user code and substitutions see where the action runs."""
        return PerformContext(action.configurations, _launch_file_seen(action),
                              event_locals={"event": event or LaunchEvent()})

    def _environ_of(self, action: ActionPlan) -> dict[str, str | None]:
        """What os.environ is when launch performs the action: its scope's during the
        visit of the file (no trigger), the launch's when an event (a timer too) runs it."""
        return action.environ if action.trigger is None else self.core.plan.environ

    def _run_callbacks(self, action: ActionPlan, event: LaunchEvent) -> bool:
        """Launch-file functions called with the event; what they return is carried out."""
        core = self.core
        try:
            with shown_environ(core.plan.environ), captured_environ() as written:
                produced = self._call_back(action, event)
            # a callback's writes to os.environ stay for what follows, as in launch
            core.plan.environ.update(written)
        except Exception as exc:  # a user's callback must never stop the launch
            core.log_action(action, f"event callback ({action.origin}) raised "
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

    def _call_back(self, action: ActionPlan, event: LaunchEvent) -> list[Any]:
        source = action.source
        launcher = getattr(source, "launcher", None)
        produced: list[Any] = []
        for callback in source.callbacks:
            if launcher is not None:
                with launcher.capture() as added:
                    produced += entity_list(callback(event)) + added
            else:
                produced += entity_list(call_handler(callback, event, action))
        return produced

    def _carry_out(self, action: ActionPlan, entity: Entity, event: EventInfo) -> bool:
        """Log lines and shutdown at once; False for what must be resolved into the plan."""
        if isinstance(entity, LogInfo):
            self.core.log_action(action, self._perform(action, entity.msg, event),
                                 logger=USER_LOGGER)
        elif isinstance(entity, Shutdown):
            self._request_shutdown(self._perform(action, entity.reason, event), action)
        else:
            return False
        return True

    def dispatch_io(self, process_id: str, stream: str, lines: list[str], pid: int) -> None:
        core = self.core
        watchers = core.triggers.output_handlers(process_id, stream)
        source = core.plan.process(process_id).source if watchers else None
        for action in watchers:
            for line in lines:
                event = event_for("io", stream, process_name=process_id, pid=pid,
                                  text=(line + "\n").encode(), action=source)
                core.spawn_task(self.perform_action(action, event))


def failure_line(action: ActionPlan, exc: Exception) -> str:
    """One line: the action, where it is written, what it raised (a LaunchError already
    names its file and line)."""
    from ...errors import LaunchError

    if isinstance(exc, LaunchError):
        text = f"{action.kind} failed: {exc}"
    else:
        where = f" ({action.origin})" if action.origin else ""
        text = f"{action.kind}{where} raised {type(exc).__name__}: {exc}"
    return "; ".join(part.strip() for part in text.splitlines() if part.strip())


def _in_shutdown_handler(action: ActionPlan) -> bool:
    step = action.trigger
    while step is not None:
        if step.on == TriggerOn.SHUTDOWN:
            return True
        step = step.after
    return False


def _launch_file_seen(action: ActionPlan) -> str | None:
    """The launch file as launch's locals hold it where the action runs: during the file's
    visit, and in a TimerAction's actions (it keeps the locals it was executed with); not in
    what an event handler returns, where ThisLaunchFileDir fails as launch's does."""
    trigger = action.trigger
    while trigger is not None:
        if trigger.on != TriggerOn.TIMER:
            return None
        trigger = trigger.after
    return action.launch_file


def call_handler(callback: Any, event: EventInfo, action: ActionPlan) -> Any:
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
