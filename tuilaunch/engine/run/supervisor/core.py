"""The supervisor's state, its collaborators, and how it tells the world: events to
consumers and launch.log.

A concern that owns state of its own is an object the core holds, with a small interface,
made and tested alone: `triggers` (TriggerBook, triggers.py: what has happened, the event
handlers), `stopper` (Stopper, stopping.py: the stop escalation), `respawner` (Respawner,
respawn.py: the respawn policy and its backoff), `placing` (Placing, placed.py: which
machine runs what). What acts on the run's shared state (the states, the running processes,
the tasks) is a behaviour of its own, one per file, each holding this core and handed the
other behaviours it calls: PlanActions (plan_actions.py), Starting (starting.py), Ending
(ending.py), Interacting (interacting.py); the Supervisor (supervisor.py) makes them and
wires them together. Every event goes through `emit`; a consumer that raises is reported
once and never stops the launch.

The state the behaviours share is public here (documented attributes), so no underscore
name crosses a module; what one file alone uses stays private to it.
"""

from __future__ import annotations

import asyncio
import sys
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ...describe.python.launch_events import EventInfo
from ...plan.model import ActionKind, ActionPlan, Plan
from ..events import Consumer, Event, Log, Output, ProcessExited
from ..plugins import ActionRunner, SupervisorPlugin
from ..process.logfiles import LogFile
from ..process.readers import ChannelReader, Running
from ..process.watchdog import Watchdog
from .placed import Placing
from .records import ProcessRecords
from .respawn import Respawner
from .stopping import CTRL_C_REASON, Stopper
from .triggers import TriggerBook


class SupervisorCore:
    """The supervisor's state, its plugins and its consumers."""

    def __init__(self, plan: Plan, log_dir: Path, sigterm_timeout: float = 5.0,
                 sigkill_timeout: float = 5.0,
                 plugins: Iterable[SupervisorPlugin] = ()) -> None:
        """`plugins` (run/plugins.py) add what `run` does not know: ROS actions, lifecycle
        nodes, components. engine/launcher.py makes a supervisor with the ROS ones."""
        self.plan = plan
        self.plugins: list[SupervisorPlugin] = []
        self.action_runners: dict[str, ActionRunner] = {}
        """The plugins' performers of action kinds `run` does not know, by kind."""
        self.detached_actions: set[str] = {ActionKind.COROUTINE}
        """Action kinds performed in the background (a trigger does not wait for them), and
        cancelled by a shutdown (launch cancels an OpaqueCoroutine's task on shutdown)."""
        self.log_dir = log_dir
        self.consumers: list[Consumer] = []
        self.states: dict[str, str] = {
            p.id: ("pending" if p.enabled else "skipped") for p in plan.processes}
        self.states.update({a.id: ("pending" if a.enabled else "skipped") for a in plan.actions})
        self.last_event: dict[tuple[str, str], EventInfo] = {}
        """The latest event of each (process, kind), handed to the actions it triggers."""
        self.shutdown_requested = False
        """A Shutdown action or an operator asked the launch to end."""
        self.launch_reasons: set[str] = {CTRL_C_REASON, "idle"}
        """Shutdown reasons of launch's own ways to end (Ctrl+C, idle, the file's Shutdown
        actions and events): ros2 launch logs no such reason, so neither does headless;
        tuilaunch's own ways (the TUI's quit, `tuilaunch stop`, SIGHUP) say theirs."""
        self.detached_tasks: dict[str, asyncio.Task[Any]] = {}
        """Running call_service / set_parameters actions: the shutdown stops them as it
        stops processes (simple_launch runs them as nodes), and their exit handlers run."""
        self.actions_stopping: list[asyncio.Task[Any]] = []
        """The detached actions the shutdown cancelled, until they have ended: the run
        waits for them (and so for their exit handlers), whether or not a process is still
        stopping meanwhile."""
        self.failed_parts: set[str] = set()
        """What failed inside a process (a component its container could not load), by id:
        the launch then ends non-zero, as the action that loads it would."""
        self.records = ProcessRecords()
        """What is kept of each process besides its state and its child: its last exit and
        crash, its respawn wait, the operator's tool, terminal and log level (records.py)."""
        self.running: dict[str, Running] = {}
        """The processes that run now, by id: their process, pty or pipes, readers."""
        self.lingering: set[ChannelReader] = set()
        """Output still open after its process exited (a grandchild holds the pipe)."""
        self.busy = 0
        """Triggers sleeping or respawns scheduled: the run is not over while any is."""
        self.tasks: set[asyncio.Task[Any]] = set()
        """The supervisor's background tasks (`spawn_task`), cancelled at the end of a run."""
        self.shutting_down = False
        """The launch is stopping: nothing new starts, waits should give up."""
        self.changed = asyncio.Event()
        """Set at every event: the run loop looks again whether the launch is over."""
        self.keep_alive = False
        """Only shutdown ends the run (an interactive UI), not every process having exited."""
        self.reported: set[str] = set()
        """Failures already said once (a consumer that keeps raising)."""
        self.env_cache: dict[str, str] | None = None
        """The environment the processes start from, built once."""
        self.watchdog = Watchdog()
        self.triggers = TriggerBook()
        """What has happened, and the event handlers by event."""
        self.stopper = Stopper(sigterm_timeout, sigkill_timeout, self.emit,
                               lambda: self.shutting_down)
        """The stop escalation: SIGINT, SIGTERM, SIGKILL, and how hard the shutdown stops."""
        self.respawner = Respawner()
        """Whether a process that died comes back, after how long."""
        self.placing = Placing()
        """Which machine this supervisor is, and who starts the others' processes."""
        for plugin in plugins:
            self.add_plugin(plugin)
        log_dir.mkdir(parents=True, exist_ok=True)
        self.launch_log = LogFile(log_dir / "launch.log", self.report_io)
        """launch.log: every event but output, one line each."""

    @property
    def retries(self) -> dict[str, int]:
        """Respawns of each process so far."""
        return self.respawner.retries

    def flag(self, process_id: str, what: str) -> asyncio.Event:
        """Set when `what` ("start", "exit", "state:...") of `process_id` has happened."""
        return self.triggers.flag(process_id, what)

    def runs_here(self, process_id: str) -> bool:
        """Whether this supervisor spawns it (actions always run where the launch runs)."""
        return self.placing.runs_here(self.plan, process_id)

    def add_plugin(self, plugin: SupervisorPlugin) -> None:
        """Plugs in before `run`: its action kinds join those the supervisor performs."""
        self.plugins.append(plugin)
        self.action_runners.update(plugin.actions())
        self.detached_actions.update(plugin.detached_actions)

    def subscribe(self, consumer: Consumer) -> None:
        self.consumers.append(consumer)

    def emit(self, event: Event) -> None:
        """Tells every consumer; one that raises is reported once and never stops us."""
        if not isinstance(event, Output):
            # `tuilaunch logs` tells a process's life from these lines (log_reader.life_events):
            # a stop asked for is no crash, and a log line keeps its level; reason comes last
            requested = 1 if isinstance(event, ProcessExited) and event.asked else None
            level = event.level if event.level != "INFO" else None
            detail = " ".join(f"{k}={v}" for k, v in (("pid", event.pid), ("code", event.code),
                                                       ("requested", requested),
                                                       ("level", level),
                                                       ("reason", event.reason)) if v is not None)
            logger = (event.data or {}).get("logger")
            if isinstance(event, Log) and logger:  # a LogInfo line, as ros2 launch logs it
                detail = f"[{event.level}] [{logger}]: {event.reason}"
            self.launch_log.write(f"{event.time:.6f} {event.kind} {event.process or ''} "
                                   f"{detail}\n".encode())
        for consumer in list(self.consumers):
            try:
                consumer(event)
            except Exception as exc:
                self._consumer_failed(consumer, exc)
        if not isinstance(event, Output):  # output settles nothing: no wake-up of `run` per block
            self.changed.set()

    def log(self, text: str, level: str = "INFO") -> None:
        """A line for the launch pane and launch.log from whoever runs the supervisor."""
        self.emit(Log(None, reason=text, level=level))

    def _consumer_failed(self, consumer: Consumer, exc: Exception) -> None:
        name = getattr(consumer, "__qualname__", type(consumer).__name__)
        text = f"{name} failed on an event: {type(exc).__name__}: {exc}"
        if text in self.reported:
            return
        self.reported.add(text)
        self.launch_log.write(f"{time.time():.6f} error  reason={text}\n".encode())
        to_stderr(f"tuilaunch: {text}; the launch goes on")

    def report_io(self, text: str) -> None:
        """A log file that cannot be written: said to the consumers (on stderr without)."""
        if not self.consumers:
            to_stderr(f"tuilaunch: {text}")
        event = Log(None, reason=text, level="ERROR")
        for consumer in list(self.consumers):
            try:
                consumer(event)
            except Exception as exc:
                self._consumer_failed(consumer, exc)

    def spawn_task(self, coro: Any) -> None:
        """Runs `coro` in the background, kept in `tasks`; a failure is reported."""
        task = asyncio.ensure_future(coro)
        self.tasks.add(task)
        task.add_done_callback(self._task_done)

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        self.tasks.discard(task)
        if not task.cancelled() and task.exception() is not None:
            exc = task.exception()
            self.report_io(f"internal error: {type(exc).__name__}: {exc}")
            self.changed.set()

    def log_action(self, action: ActionPlan, text: str, level: str = "INFO",
                   logger: str | None = None) -> None:
        """A line in the launch pane on behalf of one action of the plan; `logger` names
        who says it in headless output and launch.log (LogInfo: launch's `launch.user`)."""
        self.emit(Log(action.id, reason=text, level=level,
                      data={"logger": logger} if logger else None))


def to_stderr(text: str) -> None:
    """A message for the operator; a dead terminal must not turn it into a failure."""
    try:
        sys.stderr.write(text + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass
