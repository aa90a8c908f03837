"""What a session client knows of its session, read from the server's events: the states,
pids and ends of its processes, its lifecycle nodes, why it began to stop, the plan it
runs, and what happened before the client came (`history`).

RemoteSupervisor holds one (`state`) and reads its LaunchPort members here; it keeps the
connection, the link and its reconnection. A batch of events is `take`n: each event is
decoded once, noted, and handed to the consumers; a subscription's reply (the first, or a
reconnection's) is `begin`, and what it says happened before is `replay`.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..engine.plan.model import Plan
from ..engine.plan.session import Session
from ..engine.run import events as ev
from ..engine.run.session.connection import Connection
from ..engine.run.session.log_reader import LogLine, tail_lines
from ..engine.run.session.protocol import Stamps, event_from_dict
from ..engine.run.vocabulary.requests import GetPlan, ReadLog
from .gaps import Gaps
from .history import merged
from .remote_lifecycle import RemoteLifecycle
from .served_session import ServedSession

Consumer = Callable[[ev.Event], None]


def merged_usage(held: dict[str, Any], moved: dict[str, Any]) -> dict[str, Any]:
    """The figures held, with the ones a `resources` event says moved. A process whose
    figures are all None has stopped, and is left out; one whose figures are not shown
    (watch_resources `processes`: None figures) keeps its growing-memory mark."""
    usage = dict(held)
    for process, figures in moved.items():
        if isinstance(figures, dict):
            usage[process] = {**usage.get(process, {}), **figures}
    return {p: f for p, f in usage.items() if f.get("rss_bytes") is not None
            or f.get("growing")}


class SessionState:
    """A session as its events tell it, and the consumers they are handed to.

    `remote`: the stream comes over an ssh link, whose output events leave their ROS
    stamps out and are numbered here (`Output.data["line"]`, for `read_stamps`)."""

    def __init__(self, session: Session, gaps: Gaps, lifecycle: RemoteLifecycle,
                 remote: bool) -> None:
        self.session = session
        self.gaps = gaps
        self.lifecycle = lifecycle
        self.remote = remote
        self.states: dict[str, str] = {}
        self.pids: dict[str, int] = {}  # from the started events, those replayed too
        self.exit_codes: dict[str, int] = {}
        self.reasons: dict[str, str] = {}
        """How each process last ended or failed to start (`exit code 1`, `killed by
        SIGSEGV`), as the server said it: what the shell is told after a failed run."""
        self.crashed: dict[str, str] = {}
        """How each process last died unasked (a crash a respawn outlived too): the exit
        status counts them, so the shell is told of them after the run."""
        self.shutdown_reason: str | None = None
        """Why the session began to stop, as its server said (`tuilaunch stop`, another
        client's quit, a signal): a client that did not ask says it before leaving."""
        self.history: list[ev.Event] = []
        self.consumers: list[Consumer] = []
        self.usage: dict[str, Any] = {}  # the figures of `resources`, which sends changes
        self.stamps = Stamps()  # the current batch's output stamps

    @property
    def plan(self) -> Plan:
        return self.session.plan

    # --- a subscription's reply ----------------------------------------------------------

    async def begin(self, result: dict[str, Any], conn: Connection,
                    timeout: float | None = None) -> None:
        """A subscription's reply (the first, or a reconnection's): the states it holds, the
        plan the server runs (asked of it within `timeout` when its file is read there),
        its values (a plan resolved here from them can take a while: not timed)."""
        self.usage = {}
        self.states = dict(result["states"])
        self.lifecycle.states.update(result.get("lifecycle") or {})
        if isinstance(self.session, ServedSession):
            await asyncio.wait_for(self.fetch_plan(conn), timeout)
        self.adopt(result["arguments"])

    async def replay(self, result: dict[str, Any], conn: Connection, log_dir: Path) -> None:
        """What happened before this client came: the last `scrollback` lines of each log
        file up to the subscription's offsets (read through the server over a link, the
        files being over there) and the state events it kept, in time order."""
        scrollback = self.gaps.scrollback
        lines: dict[str, list[LogLine]] = {}
        for process, end in result["offsets"].items():
            if self.remote:
                page = await conn.call(ReadLog(process=process, end=end, limit=scrollback,
                                               tail=True))
                lines[process] = [LogLine(*line) for line in page["lines"]]
            else:
                lines[process] = tail_lines(log_dir / f"{process}.log", end, scrollback)
        self.history = merged(lines, result["recent"])
        self._note_ends(self.history)
        if self.remote:
            self.gaps.heard(result["recent"])

    def caught_up(self, kept: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """The state events a reconnection's server kept (`kept`) after the last one heard,
        their ends noted, to be delivered."""
        recent = [data for data in kept if float(data.get("time") or 0.0) > self.gaps.last_event]
        self.gaps.heard(recent)
        for data in recent:
            event = event_from_dict(data)
            if isinstance(event, ev.ProcessExited) and event.process and event.code is not None:
                self.exit_codes[event.process] = event.code
                self._note_crash(event)
        return recent

    async def fetch_plan(self, conn: Connection) -> None:
        """The plan the server runs, for a session whose file is read there (ServedSession);
        before `run` reads the connection, or from `run` itself."""
        assert isinstance(self.session, ServedSession)
        self.session.adopt(await conn.call(GetPlan()))

    def adopt(self, arguments: dict[str, str], relaunched: bool = False) -> None:
        """Another client relaunched with these values: resolve the same plan here.
        `relaunched`: the server read the launch file again, so it is read here too (an
        edited file with the same values is a relaunch as well)."""
        if isinstance(self.session, ServedSession) or (
                arguments == self.session.arguments and not relaunched):
            return
        preview = self.session.preview(arguments, reread=relaunched)
        if preview.plan is not None:
            self.session.accept(preview)

    # --- the stream ----------------------------------------------------------------------

    def take(self, message: dict[str, Any]) -> None:
        """A batch of events (or one, in a batch that switched panes): noted, delivered."""
        self.states.update(message.get("states") or {})
        for data in message.get("events") or []:
            if "stamps" in data:
                self.stamps.unpack(data)
            event = event_from_dict(data)
            if isinstance(event, ev.Output) and event.process:
                self.gaps.count(event.process, len(event.lines))
                if self.remote:  # only a link's stream leaves stamps out
                    event.data = {**(event.data or {}),
                                  "line": self.gaps.number(len(event.lines))}
            elif isinstance(event, ev.Dropped) and event.process:
                # in the file, not sent to us: where, for a display to read them back
                event.data = self.gaps.where(event.process)
                self.gaps.count(event.process, event.code or 0)
            else:
                self.gaps.last_event = max(self.gaps.last_event, event.time)
            if isinstance(event, ev.Relaunched):
                self.adopt(dict(item.split(":=", 1) for item in event.lines), True)
            self._note_pid(event)
            if isinstance(event, ev.ProcessExited) and event.process and event.code is not None:
                self.exit_codes[event.process] = event.code
                self._note_crash(event)
            if isinstance(event, (ev.ProcessExited, ev.Failed)) and event.process and event.reason:
                self.reasons[event.process] = event.reason
            if isinstance(event, ev.Shutdown):
                self.shutdown_reason = event.reason or "stop requested"
            if isinstance(event, ev.LifecycleChanged) and event.process:
                self.lifecycle.follow(event.process, event.reason or "")
            if isinstance(event, ev.Resources):
                self.usage = merged_usage(self.usage, event.data or {})
                event.data = dict(self.usage)  # the consumers get them all
            self.deliver(event)

    def deliver(self, event: ev.Event) -> None:
        for consumer in list(self.consumers):
            consumer(event)

    def say(self, text: str, level: str = "INFO") -> None:
        """A line of this client's own (a lost link, a reconnection) to the consumers."""
        self.deliver(ev.Log(reason=text, level=level))

    def _note_ends(self, events: list[ev.Event]) -> None:
        """How processes ended before this client came (the server's recent events)."""
        for event in events:
            self._note_pid(event)
            if isinstance(event, (ev.ProcessExited, ev.Failed)) and event.process and event.reason:
                self.reasons[event.process] = event.reason
            if isinstance(event, ev.ProcessExited) and event.process:
                self._note_crash(event)

    def _note_pid(self, event: ev.Event) -> None:
        if event.process is None:
            return
        if isinstance(event, ev.Started) and event.pid is not None:
            self.pids[event.process] = event.pid
        elif isinstance(event, (ev.ProcessExited, ev.Failed)):
            self.pids.pop(event.process, None)

    def _note_crash(self, event: ev.ProcessExited) -> None:
        """An exit nobody asked for with a non-zero status: the run's exit status is 1."""
        assert event.process is not None
        if event.crashed:
            self.crashed[event.process] = event.reason or f"exit code {event.code}"
