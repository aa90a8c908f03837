"""The supervisor's state, and how it tells the world: events to consumers and launch.log.

`SupervisorCore` is the base of the supervisor's layers (core <- triggers <- plan_actions <-
stopping <- respawn <- starting <- interacting <- supervisor): each file holds one concern of
the run and the `Supervisor` (run/supervisor.py) is the whole. Every event goes through `emit`; a
consumer that raises is reported once and never stops the launch.
"""

from __future__ import annotations

import asyncio
import sys
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ..describe.launch_events import EventInfo
from ..plan.model import ActionPlan, Plan
from .events import Consumer, Event
from .logfiles import LogFile
from .plugins import ActionRunner, SupervisorPlugin
from .process_command import StartCommand
from .readers import ChannelReader, Running
from .watchdog import Watchdog


class SupervisorCore:
    """The supervisor's state, its plugins and its consumers."""

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
        self.run_prefixes: dict[str, str] = {}
        """An operator's tool (`gdb -q -ex run --args`) a process runs under, from a
        `restart` with a prefix until the next restart without one."""
        self.log_levels: dict[str, str] = {}
        """`--log-level` given at a restart, kept across respawns until a restart changes it."""
        self.started_with: dict[str, StartCommand] = {}
        """The last start of each process, exactly (status's command line)."""
        self.deaths: dict[str, dict[str, str]] = {}
        """A crash's `signal` name and `core` location, until the process starts again."""
        self.watchdog = Watchdog()
        for plugin in plugins:
            self.add_plugin(plugin)
        log_dir.mkdir(parents=True, exist_ok=True)
        self._launch_log = LogFile(log_dir / "launch.log", self._report_io)

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
        to_stderr(f"tuilaunch: {text}; the launch goes on")

    def _report_io(self, text: str) -> None:
        """A log file that cannot be written: said to the consumers (on stderr without)."""
        if not self.consumers:
            to_stderr(f"tuilaunch: {text}")
        event = Event("log", None, reason=text, level="ERROR")
        for consumer in list(self.consumers):
            try:
                consumer(event)
            except Exception as exc:
                self._consumer_failed(consumer, exc)

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

    def _log(self, action: ActionPlan, text: str, level: str = "INFO") -> None:
        self.emit(Event("log", action.id, reason=text, level=level))

    # Made by the later layers; declared here so the earlier ones can call them.

    async def start(self, process_id: str) -> None:
        raise NotImplementedError  # run/starting.py

    async def stop(self, process_id: str) -> None:
        raise NotImplementedError  # run/stopping.py

    async def shutdown(self, reason: str = "shutdown") -> None:
        raise NotImplementedError  # run/stopping.py

    async def _run_action(self, action: ActionPlan, event: EventInfo | None = None) -> None:
        raise NotImplementedError  # run/plan_actions.py


def to_stderr(text: str) -> None:
    """A message for the operator; a dead terminal must not turn it into a failure."""
    try:
        sys.stderr.write(text + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
