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

from .output import LineSplitter, strip_ansi
from .params import write_parameter_file
from .plan import ActionPlan, Plan, ProcessPlan, Trigger

_PR_SET_PDEATHSIG = 1


def _die_with_parent() -> None:
    """Runs in the child before exec: SIGKILL it when the launching thread dies."""
    try:
        ctypes.CDLL(None, use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    except (OSError, AttributeError):
        pass


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
    time: float = field(default_factory=time.time)


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
                 sigkill_timeout: float = 5.0) -> None:
        self.plan = plan
        self.log_dir = log_dir
        self.sigterm_timeout = sigterm_timeout
        self.sigkill_timeout = sigkill_timeout
        self.consumers: list[Consumer] = []
        self.states: dict[str, str] = {
            p.id: ("pending" if p.enabled else "skipped") for p in plan.processes}
        self.exit_codes: dict[str, int] = {}
        self._running: dict[str, _Running] = {}
        self._happened: dict[tuple[str, str], asyncio.Event] = {}
        self._busy = 0  # triggers sleeping or respawns scheduled
        self._tasks: set[asyncio.Task[Any]] = set()
        self._shutting_down = False
        self._changed = asyncio.Event()
        self._retries: dict[str, int] = {}
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

    async def run(self) -> int:
        """Runs until nothing can happen any more, or shutdown; returns an exit status."""
        for proc in self.plan.processes:
            if proc.enabled:
                self._spawn_task(self._when_ready(proc.trigger, self.start, proc.id))
        for action in self.plan.actions:
            if action.enabled and action.kind == "log":
                self._spawn_task(self._when_ready(action.trigger, self._run_log, action))
        while not self._settled():
            self._changed.clear()
            await self._changed.wait()
        await self._drain()
        self._launch_log.close()
        self._remove_parameter_files()
        failed = [pid for pid, state in self.states.items() if state == "failed"]
        bad_exit = [pid for pid, code in self.exit_codes.items() if code != 0]
        return 1 if failed or bad_exit else 0

    def _spawn_task(self, coro: Any) -> None:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def _settled(self) -> bool:
        if self._running or self._busy:
            return False
        if self._shutting_down:
            return True
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

    async def _run_log(self, action: ActionPlan) -> None:
        self._emit(Event("log", reason=str(action.data)))

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
                self._emit(Event("output", running.plan.id, stream=name, lines=lines))
            if not chunk:
                return

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

    async def restart(self, process_id: str) -> None:
        await self.stop(process_id)
        await self.start(process_id)

    async def shutdown(self, reason: str = "shutdown") -> None:
        if self._shutting_down:
            return
        self._shutting_down = True
        self._emit(Event("shutdown", reason=reason))
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


def _describe_exit(code: int) -> str:
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"
