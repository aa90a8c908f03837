"""An in-memory session for the TUI's tests: a `LaunchPort` (client/port.py) with no server
behind it. The test says what the session tells (`tell`: events, and the states they
bring), and reads what the TUI asked of it (`asked`: every command and request, in order).

It stands in for `RemoteSupervisor` below the App, so the App's rules (what a key does on a
row, which answer a question starts on, what the status line says) are tested under Pilot
in tests/unit, in milliseconds, with no process, socket or DDS. What needs a real session
(its timing, a real terminal's bytes, the server's own refusals) stays in
tests/integration, on the path users run.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

from tuilaunch.client.port import VERBS, Verb
from tuilaunch.engine.plan.model import Plan, PlanDiff, diff_plans
from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.events import (
    ActionFinished,
    Consumer,
    Event,
    Failed,
    LifecycleChanged,
    ProcessExited,
    Relaunched,
    Respawning,
    Started,
    Stopping,
)
from tuilaunch.engine.run.vocabulary.request import Request, to_message
from tuilaunch.engine.run.vocabulary.requests import Apply, Restart, RunAction, ShutdownLaunch

R = TypeVar("R")

EMPTY_GRAPH: dict[str, Callable[..., Any]] = {
    "nodes": lambda **_: {"nodes": []},
    "services": lambda **_: {"services": []},
    "topics": lambda **_: {"topics": []},
}
"""A ROS graph with nothing discovered yet: the Services, Params and Topics tabs ask it."""


class MemoryLifecycle:
    """The lifecycle states the session's events said, and the transitions asked."""

    def __init__(self, asked: list[tuple[str, dict[str, Any]]]) -> None:
        self.states: dict[str, str] = {}
        self._asked = asked

    async def request(self, process: str, transition: str) -> bool:
        self._asked.append(("transition", {"process": process, "transition": transition}))
        return True


class MemoryPort:
    """A session in memory: states follow the events told, as a server's would (a start
    runs, a stop is stopping, an exit is exited or failed); commands are recorded and,
    unless `answers` says otherwise, succeed without changing anything (the test tells
    the events that a real server would send back)."""

    def __init__(self, plan: Plan, name: str = "mem", log_dir: Path | None = None,
                 host: str | None = None) -> None:
        self.name = name
        self.host = host
        self.log_dir = log_dir or Path("/nonexistent/tuilaunch-memory-port")
        # a server's states hold its plan's actions too (set_parameters, call_service)
        self.states: dict[str, str] = {
            p.id: "pending" if p.enabled else "skipped" for p in [*plan.processes,
                                                                  *plan.actions]}
        self.pids: dict[str, int] = {}
        self.reasons: dict[str, str] = {}
        self.crashed: dict[str, str] = {}
        self.history: list[Event] = []
        self.asked: list[tuple[str, dict[str, Any]]] = []
        """What the TUI asked, in order: ("stop", {"process": ...}), ("status", {...})."""
        self.answers: dict[str, Callable[..., Any]] = dict(EMPTY_GRAPH)
        """A request's answer by its op (`status`, `topics`, ...): called with its fields;
        an exception it raises is the session's refusal. The graph's start empty."""
        self.plan = plan
        """The plan the session runs: a relaunch (F5) replaces it."""
        self.session: Session | None = None
        """The TUI's session, when the test gives it: another client's relaunch (a
        `Relaunched` told) resolves its values there, as RemoteSupervisor does."""
        self._lifecycle = MemoryLifecycle(self.asked)
        self.read_only = False
        self.detached = False
        self.lost = False
        self.killed_server = False
        self.shutdown_reason: str | None = None
        self.link_lost: str | None = None
        self.lost_reason: str | None = None
        self.attempt = 0
        self.attempt_since: float | None = None
        self.only: str | None = None
        self.stamps_shown = False
        self.silence = 0.0
        """What `silent_for` says: a link's seconds without a word."""
        self._consumers: list[Consumer] = []
        self._lock = threading.Lock()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._ended: asyncio.Event | None = None
        self._status = 0

    @property
    def lifecycle(self) -> MemoryLifecycle:
        return self._lifecycle

    # --- the test's side -----------------------------------------------------------------

    def tell(self, *events: Event) -> None:
        """The session says these events: states follow, each consumer (the App's buffer,
        drained on its tick) is handed them."""
        with self._lock:
            for event in events:
                self._follow(event)
                for consumer in list(self._consumers):
                    consumer(event)

    def happened(self, *events: Event) -> None:
        """What the session said before the TUI came: its history, which the TUI shows
        (as no news) when it follows the session, as an attached client's; states follow."""
        with self._lock:
            for event in events:
                self._follow(event)
                self.history.append(event)

    def end(self, status: int = 0, reason: str | None = None) -> None:
        """The session ends (its server said `ended`)."""
        self.shutdown_reason = reason
        self._status = status
        if self._loop is not None and self._ended is not None:
            self._loop.call_soon_threadsafe(self._ended.set)

    def ops(self) -> list[str]:
        return [op for op, _ in self.asked]

    def _follow(self, event: Event) -> None:
        if isinstance(event, Relaunched) and self.session is not None:
            preview = self.session.preview(dict(item.split(":=", 1) for item in event.lines),
                                           reread=True)
            if preview.plan is not None:
                self.plan = self.session.accept(preview)
        process = event.process
        if process is None:
            return
        if isinstance(event, Started):
            self.states[process] = "running"
            if event.pid is not None:
                self.pids[process] = event.pid
        elif isinstance(event, Stopping):
            self.states[process] = "stopping"
        elif isinstance(event, Respawning):
            self.states[process] = "respawning"
        elif isinstance(event, (ProcessExited, Failed)):
            self.pids.pop(process, None)
            crashed = isinstance(event, ProcessExited) and event.crashed
            self.states[process] = "failed" if crashed or isinstance(event, Failed) \
                else "exited"
            if event.reason:
                self.reasons[process] = event.reason
        elif isinstance(event, ActionFinished):
            self.states[process] = event.reason or "done"
        elif isinstance(event, LifecycleChanged):
            self._lifecycle.states[process] = event.reason or ""

    # --- LaunchPort -------------------------------------------------------------------------

    def subscribe(self, consumer: Consumer) -> None:
        with self._lock:
            self._consumers.append(consumer)

    async def run(self, keep_alive: bool = True) -> int:
        self._loop = asyncio.get_running_loop()
        self._ended = asyncio.Event()
        await self._ended.wait()
        return 0 if self.detached else self._status

    async def request(self, request: Request[R]) -> R:
        fields = to_message(request)  # as the wire says it: the fields not at their default
        op = fields.pop("op")
        self.asked.append((op, fields))
        answer = self.answers.get(op)
        return request.reply(answer(**fields) if answer is not None else {})

    async def command(self, verb: Verb, process: str) -> None:
        await self.request(VERBS[verb](process))

    async def restart(self, process_id: str, prefix: str | None = None,
                      log_level: str | None = None, terminal: bool = False) -> None:
        await self.request(Restart(process=process_id, prefix=prefix, log_level=log_level,
                                   terminal=terminal))

    async def run_action(self, action_id: str) -> None:
        await self.request(RunAction(action=action_id))

    async def replace_plan(self, plan: Plan) -> PlanDiff:
        """A relaunch: what it stops and starts is told by the test (its events), what it
        would is answered, as a server's diff of the two plans."""
        await self.request(Apply(arguments={a.name: a.value for a in plan.arguments}))
        running = {p for p, s in self.states.items() if s == "running"}
        diff = diff_plans(self.plan, plan, running)
        self.plan = plan
        for proc in plan.processes:
            self.states.setdefault(proc.id, "pending" if proc.enabled else "skipped")
        return diff

    async def show(self, process: str | None) -> None:
        self.only = process

    async def read_stamps(self, shown: bool, since: int | None,
                          ) -> tuple[int, int, dict[int, int]]:
        self.stamps_shown = shown
        return 0, 0, {}

    async def shutdown(self, reason: str = "shutdown") -> None:
        await self.request(ShutdownLaunch(reason=reason))
        self.end(0, reason)

    async def detach(self) -> None:
        self.detached = True
        self.asked.append(("detach", {}))
        self.end(0)

    def kill_all(self) -> None:
        self.asked.append(("kill", {}))

    def silent_for(self) -> float:
        return self.silence

    def retry_now(self) -> None:
        self.asked.append(("retry", {}))
