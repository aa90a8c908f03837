"""Run a Plan: start processes, read their output, fire triggers, respawn, shut down.

Each process gets its own process group and dies with tuilaunch even if tuilaunch is
killed (PR_SET_PDEATHSIG). Every output line goes to the process's log file before any
consumer sees it; consumers only get events.
"""

from __future__ import annotations

import asyncio
import ctypes
import os
import signal
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from ..describe.entities import Entity, LogInfo, Shutdown, entity_list
from ..describe.substitutions import PerformContext, perform
from ..plan.model import ActionPlan, Plan, PlanDiff, ProcessPlan, Trigger, diff_plans
from ..plan.params import write_parameter_file
from ..ros.messages import MessageError
from .output import LineSplitter, strip_ansi

ROS_ACTIONS = ("call_service", "set_parameters")

_PR_SET_PDEATHSIG = 1


try:  # looked up once here: the child between fork and exec should do as little as possible
    _prctl: Any = ctypes.CDLL(None, use_errno=True).prctl
except (OSError, AttributeError):
    _prctl = None


def _die_with_parent() -> None:
    """Runs in the child before exec: SIGKILL it when the launching thread dies."""
    if _prctl is not None:
        _prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)


@dataclass
class Event:
    """What consumers (the headless printer, the TUI) are told."""

    kind: str  # started | output | exited | failed | respawning | log | shutdown
    process: str | None = None
    pid: int | None = None
    stream: str | None = None
    lines: list[str] = field(default_factory=list)
    code: int | None = None
    reason: str | None = None
    level: str = "INFO"
    time: float = field(default_factory=time.time)


@dataclass
class LaunchEvent:
    """What launch-file callbacks receive: `event.text`, `event.returncode`, `event.reason`."""

    process_name: str | None = None
    pid: int | None = None
    text: bytes = b""
    returncode: int | None = None
    reason: str = ""


Consumer = Callable[[Event], None]


@dataclass
class _Running:
    plan: ProcessPlan
    process: asyncio.subprocess.Process
    log: IO[str]
    started: float
    stopping: bool = False
    readers: list[asyncio.Task[None]] = field(default_factory=list)


class Supervisor:
    def __init__(self, plan: Plan, log_dir: Path, sigterm_timeout: float = 5.0,
                 sigkill_timeout: float = 5.0,
                 bridge_factory: Callable[[], Any] | None = None,
                 service_timeout: float = 10.0) -> None:
        self.plan = plan
        self.service_timeout = service_timeout
        self._bridge: Any = None
        self._bridge_factory = bridge_factory  # whoever supplies the bridge also closes it
        self.log_dir = log_dir
        self.sigterm_timeout = sigterm_timeout
        self.sigkill_timeout = sigkill_timeout
        self.consumers: list[Consumer] = []
        self.states: dict[str, str] = {
            p.id: ("pending" if p.enabled else "skipped") for p in plan.processes}
        self.states.update({a.id: ("pending" if a.enabled else "skipped") for a in plan.actions})
        self._io_watchers: dict[tuple[str, str], list[ActionPlan]] = {}
        self._on_shutdown: list[ActionPlan] = []
        self.exit_codes: dict[str, int] = {}
        self._running: dict[str, _Running] = {}
        self._happened: dict[tuple[str, str], asyncio.Event] = {}
        self._busy = 0  # triggers sleeping or respawns scheduled
        self._tasks: set[asyncio.Task[Any]] = set()
        self._shutting_down = False
        self._changed = asyncio.Event()
        self._retries: dict[str, int] = {}
        self._keep_alive = False
        log_dir.mkdir(parents=True, exist_ok=True)
        self._launch_log = open(log_dir / "launch.log", "a", buffering=1)

    # --- events ----------------------------------------------------------------------

    def subscribe(self, consumer: Consumer) -> None:
        self.consumers.append(consumer)

    def _emit(self, event: Event) -> None:
        if event.kind != "output":
            detail = " ".join(f"{k}={v}" for k, v in (("pid", event.pid), ("code", event.code),
                                                       ("reason", event.reason)) if v is not None)
            self._launch_log.write(f"{event.time:.3f} {event.kind} {event.process or ''} "
                                   f"{detail}\n")
        for consumer in list(self.consumers):
            consumer(event)
        self._changed.set()

    def _flag(self, process_id: str, what: str) -> asyncio.Event:
        return self._happened.setdefault((process_id, what), asyncio.Event())

    # --- running ---------------------------------------------------------------------

    async def run(self, keep_alive: bool = False) -> int:
        """Runs until nothing can happen any more, or shutdown; returns an exit status.

        With keep_alive (an interactive UI), only shutdown ends the run: an operator who
        stops every process still wants to start them again."""
        self._keep_alive = keep_alive
        for proc in self.plan.processes:
            if proc.enabled:
                self._spawn_task(self._when_ready(proc.trigger, self.start, proc.id))
        for action in self.plan.actions:
            if action.enabled:
                self._schedule_action(action)
        while not self._settled():
            self._changed.clear()
            await self._changed.wait()
        await self._drain()
        if self._bridge is not None and self._bridge_factory is None:
            await asyncio.to_thread(self._bridge.close)
        self._launch_log.close()
        self._remove_parameter_files()
        failed = [item for item, state in self.states.items() if state == "failed"]
        bad_exit = [pid for pid, code in self.exit_codes.items() if code != 0]
        return 1 if failed or bad_exit else 0

    def _spawn_task(self, coro: Any) -> None:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def _settled(self) -> bool:
        if self._shutting_down:
            # waiting actions, timers and respawns are cancelled when the run drains
            return not self._running
        if self._keep_alive or self._running or self._busy:
            return False
        if any(state == "running" for state in self.states.values()):
            return False  # an action is waiting for its service or node
        # a pending item can still start only if what it waits for is alive or pending
        return not any(state == "pending" for state in self.states.values()) or all(
            not self._can_fire(p.trigger) for p in self.plan.processes
            if self.states[p.id] == "pending")

    def _can_fire(self, trigger: Trigger | None) -> bool:
        while trigger is not None:
            if trigger.target is not None and trigger.on in ("start", "exit"):
                done = self._flag(trigger.target, trigger.on).is_set()
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
                await self._flag(step.target, step.on).wait()
            if step.delay:
                self._busy += 1
                try:
                    await asyncio.sleep(step.delay)
                finally:
                    self._busy -= 1
                    self._changed.set()
            if self._shutting_down:
                return
        result = then(item)
        if asyncio.iscoroutine(result):
            await result

    # --- actions ---------------------------------------------------------------------------

    def _schedule_action(self, action: ActionPlan) -> None:
        chain = action.trigger
        while chain is not None and chain.on not in ("io", "shutdown"):
            chain = chain.after
        if chain is not None and chain.on == "shutdown":
            self._on_shutdown.append(action)
        elif chain is not None and chain.target is not None:
            key = (chain.target, chain.io or "stdout")
            self._io_watchers.setdefault(key, []).append(action)
        else:
            self._spawn_task(self._when_ready(action.trigger, self._run_action, action))

    async def _run_action(self, action: ActionPlan, event: LaunchEvent | None = None) -> None:
        self.states[action.id] = "running"
        self._emit(Event("started", action.id))
        self._flag(action.id, "start").set()
        ok = True
        try:
            if action.kind == "call_service":
                ok = await self._call_service(action)
            elif action.kind == "set_parameters":
                ok = await self._set_parameters(action)
            elif action.kind == "shutdown":
                self._spawn_task(self.shutdown(str(action.data)))
            elif action.kind == "log":
                self._log(action, self._perform(action, action.source.msg, event))
            elif action.kind == "event_callback":
                ok = self._run_callbacks(action, event or LaunchEvent())
            else:
                self._log(action, f"{action.kind} is not supported yet; skipped", "WARN")
        except asyncio.CancelledError:
            self.states[action.id] = "cancelled"
            raise
        self.states[action.id] = "done" if ok else "failed"
        self._emit(Event("finished", action.id, reason=self.states[action.id]))
        self._flag(action.id, "exit").set()

    def _log(self, action: ActionPlan, text: str, level: str = "INFO") -> None:
        self._emit(Event("log", action.id, reason=text, level=level))

    def _perform(self, action: ActionPlan, value: Any, event: LaunchEvent | None) -> str:
        context = PerformContext(action.configurations, None,
                                 event_locals={"event": event or LaunchEvent()})
        return perform(value, context)

    def bridge(self) -> Any:
        if self._bridge is None:
            if self._bridge_factory is not None:
                self._bridge = self._bridge_factory()
            else:
                from ..ros.bridge import RosBridge

                self._bridge = RosBridge()
        return self._bridge

    async def _call_service(self, action: ActionPlan) -> bool:
        from ..ros.bridge import RosError

        name = str(action.target)
        self._log(action, f"waiting for service {name}")
        try:
            bridge = self.bridge()
            service_type = await bridge.wait_for_service(name, None)
            request, response = await bridge.call_service(
                name, action.data, self.service_timeout, service_type=service_type)
        except (RosError, MessageError) as exc:
            self._log(action, f"call_service {name} failed: {exc}", "ERROR")
            return False
        if "req" in action.verbosity:
            self._log(action, f"{name} ({service_type}) request: {request}")
        if "res" in action.verbosity:
            self._log(action, f"{name} response: {response}")
        return True

    async def _set_parameters(self, action: ActionPlan) -> bool:
        from ..ros.bridge import RosError

        node = str(action.target)
        self._log(action, f"waiting for node {node}")
        try:
            bridge = self.bridge()
            await bridge.wait_for_service(f"{node}/set_parameters", None)
            results = await bridge.set_parameters(node, action.data, self.service_timeout)
        except (RosError, MessageError) as exc:
            self._log(action, f"set_parameters on {node} failed: {exc}", "ERROR")
            return False
        if "req" in action.verbosity:
            self._log(action, f"{node} parameters requested: {action.data}")
        for result in results:
            if not result.successful:
                self._log(action, f"{node} refused {result.name}="
                          f"{action.data.get(result.name)!r}: {result.reason}", "ERROR")
            elif "res" in action.verbosity:
                self._log(action, f"{node} set {result.name}={action.data.get(result.name)!r}")
        return all(r.successful for r in results)

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
        for entity in produced:
            if id(entity) in seen:
                continue
            seen.add(id(entity))
            self._carry_out(action, entity, event)
        return True

    def _carry_out(self, action: ActionPlan, entity: Entity, event: LaunchEvent) -> None:
        if isinstance(entity, LogInfo):
            self._log(action, self._perform(action, entity.msg, event))
        elif isinstance(entity, Shutdown):
            self._spawn_task(self.shutdown(self._perform(action, entity.reason, event)))
        else:
            self._log(action, f"an event callback returned {entity.describe()}, which "
                      "tuilaunch does not start at run time yet", "WARN")

    def _dispatch_io(self, process_id: str, stream: str, lines: list[str], pid: int) -> None:
        for action in self._io_watchers.get((process_id, stream), []):
            for line in lines:
                event = LaunchEvent(process_id, pid, (line + "\n").encode())
                self._spawn_task(self._run_action(action, event))

    async def start(self, process_id: str) -> None:
        """Starts one process (also a stopped or exited one, from the UI)."""
        proc = self.plan.process(process_id)
        if process_id in self._running or self._shutting_down:
            return
        if proc.error:
            self.states[process_id] = "failed"
            self._emit(Event("failed", process_id, reason=proc.error))
            return
        for path, values in proc.generated_parameter_files:
            write_parameter_file(Path(path), values)
        env = {} if proc.clear_env else dict(os.environ)
        env.update(proc.env)
        env.setdefault("PYTHONUNBUFFERED", "1")
        env.setdefault("RCUTILS_LOGGING_BUFFERED_STREAM", "1")
        env.setdefault("RCUTILS_COLORIZED_OUTPUT", "0" if os.environ.get("NO_COLOR") else "1")
        try:
            child = await asyncio.create_subprocess_exec(
                *proc.cmd, stdin=asyncio.subprocess.DEVNULL, stdout=asyncio.subprocess.PIPE,
                stderr=asyncio.subprocess.PIPE, env=env, cwd=proc.cwd, start_new_session=True,
                preexec_fn=_die_with_parent)
        except OSError as exc:
            self.states[process_id] = "failed"
            self._emit(Event("failed", process_id, reason=f"cannot start {proc.cmd[0]}: "
                             f"{exc.strerror or exc}"))
            return
        log = open(self.log_dir / f"{process_id}.log", "a", buffering=1 << 16)
        running = _Running(proc, child, log, time.monotonic())
        self._running[process_id] = running
        self.states[process_id] = "running"
        self._emit(Event("started", process_id, pid=child.pid))
        self._flag(process_id, "start").set()
        assert child.stdout is not None and child.stderr is not None
        running.readers = [asyncio.ensure_future(self._read(running, child.stdout, "stdout")),
                           asyncio.ensure_future(self._read(running, child.stderr, "stderr"))]
        self._spawn_task(self._wait(running))

    async def _read(self, running: _Running, stream: asyncio.StreamReader, name: str) -> None:
        splitter = LineSplitter()
        while True:
            chunk = await stream.read(1 << 16)
            lines = splitter.feed(chunk) if chunk else splitter.flush()
            if lines:
                stamp = f"{time.time():.6f} {name} "
                running.log.write("".join(stamp + strip_ansi(line) + "\n" for line in lines))
                # on disk at once: a tail -f sees it, and a SIGKILL of tuilaunch loses nothing
                running.log.flush()
                self._emit(Event("output", running.plan.id, stream=name, lines=lines))
                if self._io_watchers:
                    self._dispatch_io(running.plan.id, name, lines, running.process.pid)
            if not chunk:
                return
            # a flooding process must not starve the UI sharing this loop: yield between
            # chunks; the pipe then holds the producer back, and nothing is lost
            await asyncio.sleep(0)

    async def _wait(self, running: _Running) -> None:
        code = await running.process.wait()
        await asyncio.gather(*running.readers)
        running.log.close()
        process_id = running.plan.id
        del self._running[process_id]
        self.exit_codes[process_id] = code
        self.states[process_id] = "exited"
        self._emit(Event("exited", process_id, pid=running.process.pid, code=code,
                         reason=_describe_exit(code)))
        self._flag(process_id, "exit").set()
        if self._should_respawn(running, code):
            await self._respawn(running)

    def _should_respawn(self, running: _Running, code: int) -> bool:
        proc = running.plan
        if not proc.respawn or running.stopping or self._shutting_down or code == 0:
            return False  # a clean exit is a finished job, not a crash
        limit = proc.respawn_max_retries
        return limit < 0 or self._retries.get(proc.id, 0) < limit

    async def _respawn(self, running: _Running) -> None:
        proc = running.plan
        tries = self._retries[proc.id] = self._retries.get(proc.id, 0) + 1
        quick = time.monotonic() - running.started < 2.0
        # back off when it dies at once, so a crash loop does not spin the machine
        delay = max(proc.respawn_delay, 0.1) * (2 ** (tries - 1) if quick else 1)
        delay = min(delay, 30.0)
        self.states[proc.id] = "respawning"
        self._busy += 1
        self._emit(Event("respawning", proc.id, reason=f"try {tries} in {delay:g} s"))
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

        Processes whose command, environment and parameters are unchanged keep running;
        triggers of new processes fire at once when what they wait for already happened.
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
                if proc.id not in self._running:
                    self.states[proc.id] = "pending" if proc.enabled else "skipped"
            self._io_watchers.clear()
            self._on_shutdown.clear()
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
        self._emit(Event("shutdown", reason=reason))
        for action in self._on_shutdown:
            await self._run_action(action, LaunchEvent(reason=reason))
        await asyncio.gather(*(self._escalate(r) for r in list(self._running.values())))
        self._changed.set()

    async def _escalate(self, running: _Running) -> None:
        """SIGINT, then SIGTERM, then SIGKILL, to the whole process group."""
        running.stopping = True
        for sig, wait in ((signal.SIGINT, self.sigterm_timeout),
                          (signal.SIGTERM, self.sigkill_timeout), (signal.SIGKILL, None)):
            if running.process.returncode is not None:
                return
            try:
                os.killpg(running.process.pid, sig)
            except ProcessLookupError:
                return
            try:
                await asyncio.wait_for(asyncio.shield(running.process.wait()), wait)
                return
            except TimeoutError:
                continue

    def kill_all(self) -> None:
        """Last resort when the caller cannot wait (the UI is being torn down): SIGKILL."""
        for running in list(self._running.values()):
            try:
                os.killpg(running.process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        self._remove_parameter_files()

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


def _call_handler(callback: Any, event: LaunchEvent, action: ActionPlan) -> Any:
    """Plain launch API handlers take (event, context); simple_launch's take (event)."""
    import inspect

    try:
        arity = len(inspect.signature(callback).parameters)
    except (TypeError, ValueError):
        arity = 1
    if arity >= 2:
        return callback(event, PerformContext(action.configurations))
    return callback(event)


def _describe_exit(code: int) -> str:
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"
