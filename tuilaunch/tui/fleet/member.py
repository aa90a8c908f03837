"""One session of a fleet TUI (`tuilaunch attach a:x b:y`): its link, its tree, its pane.

Each member owns what the single-session TUI holds once for the app: a RemoteSupervisor on
the engine thread (its own ssh link, reconnected by itself), an EventBuffer its events
wait in, an OutputStore, and the widgets showing them (a LaunchTree whose root is the
session, an OutputPanel). Nothing is shared between members but the engine thread, so a
relaunch, a stop or a lost link of one touches nothing of another.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from dataclasses import dataclass, field

from rich.text import Text

from ...client.remote_supervisor import RemoteSupervisor
from ...client.served_session import ServedSession
from ...engine.run.event_buffer import EventBuffer
from ...engine.run.events import (
    STATE_EVENTS,
    Dropped,
    Event,
    Failed,
    LifecycleChanged,
    Log,
    Output,
    ProcessExited,
    Reading,
    Relaunched,
    Started,
    Stopping,
)
from ..lifecycle_steps import LifecycleSteps
from ..output_store import ERROR, INFO, WARN, Gap, Line, OutputStore
from ..screens.output_panel import OutputPanel
from ..screens.tree_panel import LaunchTree
from ..session_link import process_ended

COUNTED = ("running", "pending", "stopping", "exited", "failed", "respawning")


@dataclass(eq=False)
class Member:
    """A session of the fleet: `label` is how the tree names it (HOST:NAME, local:NAME)."""

    label: str
    host: str | None  # None: this computer
    name: str
    tree: LaunchTree
    pane: OutputPanel
    store: OutputStore
    session: ServedSession = field(default_factory=lambda: ServedSession("?", {}))
    buffer: EventBuffer = field(default_factory=lambda: EventBuffer(max_lines=2500))
    supervisor: RemoteSupervisor | None = None
    problem: str | None = None
    """Why the member is not followed now: cannot be reached (retrying), or ended."""
    ended: bool = False
    wake: asyncio.Event | None = None
    """Set by R: the next try to reach a session never reached, now."""
    asked_to_stop: set[str] = field(default_factory=set)
    lifecycle_steps: LifecycleSteps = field(default_factory=LifecycleSteps)
    """`]`, `[` on this session's lifecycle nodes, in the order typed."""
    on_event: Callable[[Member, Event], None] | None = None
    """Where the events for its tabs go (readings, relaunches): fleet/tabs.py."""

    @property
    def address(self) -> str:
        """As the command line takes it."""
        return self.name if self.host is None else f"{self.host}:{self.name}"

    def unavailable(self) -> str | None:
        """Why keys cannot act on this session now (None: they can)."""
        if self.supervisor is None or self.ended:
            return self.problem or "not connected"
        return self.supervisor.link_lost

    def counts(self) -> dict[str, int]:
        counts: dict[str, int] = {}
        if self.supervisor is None:
            return counts
        for process in self.session.plan.processes:
            state = self.tree.states.get(process.id) or \
                self.supervisor.states.get(process.id, "pending")
            counts[state] = counts.get(state, 0) + 1
        return counts

    def counts_text(self) -> str:
        counts = self.counts()
        return "  ".join(f"{counts[s]} {'waiting' if s == 'pending' else s}"
                         for s in COUNTED if counts.get(s))

    def root_label(self) -> Text:
        """The session's root row: its address and live counts; greyed, with why,
        while it cannot be reached."""
        label = Text(self.label, style="bold")  # its file is in the header: room for counts
        why = self.unavailable()
        if self.ended:
            label.append(f" {why}  {self.counts_text()}", "italic")
            label.stylize("dim")
        elif why is not None:
            # a link that dropped reconnects by itself; one never made says it retries
            label.append(f" {why}" + ("; reconnecting (R: now)" if self.supervisor else ""),
                         "italic")
            label.stylize("dim")
        else:
            label.append(f"  {self.counts_text()}")
        return label

    def refresh_root(self) -> None:
        self.tree.root.set_label(self.root_label())

    # --- events ------------------------------------------------------------------------------

    def show_events(self, events: list[Event]) -> None:
        """The events of a drain into this member's tree and pane (as SessionLink's, for
        the rows and the lines a fleet shows)."""
        tree, store = self.tree, self.store
        fresh: list[Line] = []
        for event in events:
            if isinstance(event, Output) and event.process:
                first = event.data.get("line") if event.data else None
                fresh += store.add(event.process, event.stream or "stdout", event.lines,
                                   first)
            elif isinstance(event, Log):
                if event.process and self.supervisor is not None:
                    state = self.supervisor.states.get(event.process, "")
                    tree.set_state(event.process, state)
                level = {"WARN": WARN, "ERROR": ERROR}.get(event.level, INFO)
                fresh += store.add_event(event.process or "launch", event.reason or "", level)
            elif isinstance(event, Reading):
                if self.on_event is not None:
                    self.on_event(self, event)
            elif isinstance(event, LifecycleChanged) and event.process:
                tree.set_lifecycle(event.process, event.reason or "")
            elif isinstance(event, Relaunched) and self.supervisor is not None:
                self.show_plan()
                if self.on_event is not None:
                    self.on_event(self, event)
            elif isinstance(event, Dropped) and event.process:
                store.count_dropped(event.process, event.code or 0)
                where = event.data or {}
                if event.code and "start" in where:
                    fresh += store.add_gap(event.process, Gap(
                        int(where["start"]), int(where["skip"]), event.code))
            elif event.process and self.supervisor is not None and \
                    isinstance(event, STATE_EVENTS):
                fresh += self._life(event)
        if fresh:
            self.pane.append(fresh)
        self.pane.flush()
        if events:
            self.refresh_root()

    def _life(self, event: Event) -> list[Line]:
        assert self.supervisor is not None and event.process is not None
        process, tree = event.process, self.tree
        state = self.supervisor.states.get(process, event.kind)
        if isinstance(event, Started):
            self.asked_to_stop.discard(process)
            self.store.reported.forget(process)
            tree.set_state(process, state, f"pid {event.pid}" if event.pid else "")
            return self.store.add_event(process, f"process started with pid [{event.pid}]")
        if isinstance(event, Stopping):
            tree.set_state(process, state, f"pid {event.pid}" if event.pid else "")
            return []
        if isinstance(event, ProcessExited):
            state, text, level = process_ended(event, state, process in self.asked_to_stop)
            tree.set_state(process, state, f"({event.reason}, pid {event.pid})")
            return self.store.add_event(process, text, level)
        tree.set_state(process, state, f"({event.reason})")
        if isinstance(event, Failed):
            return self.store.add_event(process, f"failed: {event.reason}", ERROR)
        return self.store.add_event(process, f"respawning: {event.reason}", WARN)

    def show_plan(self) -> None:
        """The session's plan as the tree's children, its root the session."""
        assert self.supervisor is not None
        self.tree.show_plan(self.session.plan, self.supervisor.states)
        for process, state in self.supervisor.lifecycle.states.items():
            self.tree.set_lifecycle(process, state)
        self.refresh_root()
