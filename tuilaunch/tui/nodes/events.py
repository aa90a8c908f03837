"""How a session's events show in a tree and a pane: a row's state and detail, a line in
the node's pane as ros2 launch prints it, a respawn's wait counted down.

One object a session (`NodeEvents`): the single TUI's Nodes tab holds one, a fleet view one
per session, so both views show a process's life in the same words.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from ...engine.plan.model import Plan
from ...engine.run.events import (
    STATE_EVENTS,
    ActionFinished,
    ComponentReport,
    Dropped,
    Event,
    ExitCause,
    Failed,
    LifecycleChanged,
    Log,
    Output,
    ProcessExited,
    Reading,
    Relaunched,
    Respawning,
    Started,
    Stopping,
)
from ..output_store import ERROR, INFO, WARN, Gap, Line, OutputStore
from ..screens.tree_panel import LaunchTree
from .respawn_countdown import RespawnCountdown

LEVELS = {"WARN": WARN, "ERROR": ERROR}


@dataclass
class Batch:
    """What a batch of events changed beyond the rows and the lines: the host's part."""

    lines: list[Line] = field(default_factory=list)
    """The pane's new lines, in order."""
    lifecycle: bool = False
    """A lifecycle node changed state: the keys that apply to it may have changed."""
    relaunched: list[Relaunched] = field(default_factory=list)
    """Relaunches (the tree shows the new plan already): the form, a note."""
    counting: bool = False
    """A respawn's wait is being counted down: `count_down` once a second until it ends."""
    readings: list[Reading] = field(default_factory=list)
    """Figures a tab asked for (rates, an echo, plot samples, CPU and memory): its own."""
    news: bool = False
    """An event came that is neither a line nor a reading (a start, an end, a state): the
    counts said beside the tree may have changed."""


class NodeEvents:
    """Shows one session's events in its tree (`tree`) and its output store (`store`).

    `states`: the session's process states as its client knows them (None until it is
    followed); `lifecycle`: its lifecycle nodes' states; `plan`: the plan it runs;
    `quitting`: whether this client is stopping the launch (every exit is then asked)."""

    def __init__(self, tree: LaunchTree, store: OutputStore,
                 plan: Callable[[], Plan],
                 states: Callable[[], Mapping[str, str] | None],
                 lifecycle: Callable[[], Mapping[str, str]] = dict,
                 quitting: Callable[[], bool] = lambda: False,
                 asked_to_stop: set[str] | None = None) -> None:
        self.tree = tree
        self.store = store
        self._plan = plan
        self._states = states
        self._lifecycle = lifecycle
        self._quitting = quitting
        self.countdown = RespawnCountdown()
        self.asked_to_stop: set[str] = set() if asked_to_stop is None else asked_to_stop
        """Stops this client asked for (the host's own set, when it keeps one): their
        non-zero exit is not a failure."""

    # --- the plan ----------------------------------------------------------------------------

    def show_plan(self) -> None:
        """The plan as the tree, with the states and lifecycle states known so far and
        what each waiting process waits for."""
        self.tree.show_plan(self._plan(), dict(self._states() or {}))
        self.show_lifecycle()
        self.describe_waiting()

    def show_lifecycle(self) -> None:
        """The lifecycle states the client knows now (after a replay of what happened
        before it came, whose lifecycle events are older)."""
        for process, state in self._lifecycle().items():
            self.tree.set_lifecycle(process, state)

    def describe_waiting(self) -> None:
        """Each process not started yet says why: its trigger, the condition that skips
        it, the error that keeps it from starting."""
        tree = self.tree
        for proc in self._plan().processes:
            if proc.enabled and proc.trigger is not None:
                tree.details[proc.id] = f"({proc.trigger.describe()})"
            elif not proc.enabled and proc.skipped_by is not None:
                tree.details[proc.id] = f"({proc.skipped_by.expression} = " \
                                        f"{proc.skipped_by.value!r})"
            elif proc.error:
                tree.details[proc.id] = f"({proc.error})"
            tree.refresh_row(proc.id)

    # --- events ------------------------------------------------------------------------------

    def show(self, events: list[Event]) -> Batch:
        """A batch of events into the rows and the store; the pane's new lines returned."""
        shown = Batch()
        tree, store = self.tree, self.store
        states = self._states()
        for event in events:
            if isinstance(event, Output) and event.process:
                if event.data and "partial" in event.data:  # a prompt waiting, unfinished
                    store.set_partial(event.process, event.stream or "stdout",
                                      str(event.data["partial"]))
                first = event.data.get("line") if event.data else None
                shown.lines += store.add(event.process, event.stream or "stdout",
                                         event.lines, first)
            elif isinstance(event, Log):
                if event.process and states is not None:
                    state = states.get(event.process, "")
                    if tree.states.get(event.process) == "respawning" != state:
                        tree.details.pop(event.process, None)  # "try 1 in 6 s": called off
                    # a detail it comes with: its machine being reached again
                    detail = (event.data or {}).get("detail")
                    tree.set_state(event.process, state, str(detail or ""))
                shown.lines += store.add_event(event.process or "launch", event.reason or "",
                                               LEVELS.get(event.level, INFO))
            elif isinstance(event, LifecycleChanged) and event.process:
                tree.set_lifecycle(event.process, event.reason or "")
                shown.lifecycle = True
            elif isinstance(event, ComponentReport) and event.data:
                data = event.data
                short = f"id {data['unique_id']}" if "unique_id" in data else \
                    str(data.get("error") or data.get("text") or "")
                tree.set_component(str(data["component"]), str(data["state"]), short)
                if data["state"] not in ("loading", "waiting"):
                    shown.lines += store.add_event(event.process or "launch",
                                                   event.reason or "",
                                                   LEVELS.get(event.level, INFO))
            elif isinstance(event, Relaunched) and states is not None:
                self.show_plan()  # any client's relaunch: the session holds the new plan
                shown.relaunched.append(event)
            elif isinstance(event, Dropped) and event.process:
                # counted in the pane's status line; where the session says where they are
                # in the log file, a line stands for them, read when scrolled back to
                store.count_dropped(event.process, event.code or 0)
                where = event.data or {}
                if event.code and "start" in where:
                    shown.lines += store.add_gap(event.process, Gap(
                        int(where["start"]), int(where["skip"]), event.code))
            elif event.process and states is not None and \
                    isinstance(event, (*STATE_EVENTS, ActionFinished)):
                shown.lines += self._life(event, states)
        shown.counting = bool(self.countdown)
        return shown

    def _life(self, event: Event, states: Mapping[str, str]) -> list[Line]:
        """A state change: the tree row, and a line in the node's pane as ros2 launch
        prints it ("process started with pid", "process has died [pid, exit code]")."""
        assert event.process is not None
        process, tree, store = event.process, self.tree, self.store
        state = states.get(process, event.kind)
        self.countdown.end(process)  # a new state: any wait counted is over
        if isinstance(event, Started):
            self.asked_to_stop.discard(process)
            # its node name is learnt again from this run's lines (a relaunch may move it)
            store.reported.forget(process)
            tree.set_state(process, state, f"pid {event.pid}" if event.pid else "")
            if any(p.id == process for p in self._plan().processes):
                return store.add_event(process, f"process started with pid [{event.pid}]")
            return []
        if isinstance(event, ProcessExited):
            state, text, level = process_ended(
                event, state, process in self.asked_to_stop or self._quitting())
            tree.set_state(process, state, f"({event.reason}, pid {event.pid})")
            return store.add_event(process, text, level)
        if isinstance(event, Failed):
            tree.set_state(process, state, f"({event.reason})")
            return store.add_event(process, f"failed: {event.reason}", ERROR)
        if isinstance(event, Respawning):
            data = event.data or {}
            detail = f"({event.reason})"
            if "delay" in data:  # counted down on the row until it comes back
                detail = self.countdown.begin(process, int(data["try"]), float(data["delay"]))
            tree.set_state(process, state, detail)
            return store.add_event(process, f"respawning: {event.reason}", WARN)
        detail = f"pid {event.pid}" if isinstance(event, Stopping) and event.pid else \
            f"({event.reason})" if event.reason else ""
        tree.set_state(process, state, detail)
        return []

    def count_down(self) -> bool:
        """Once a second while a respawn waits: its row says how long is left. False once
        no wait is left to count."""
        tree = self.tree
        for process, text in self.countdown.tick().items():
            if tree.states.get(process) != "respawning":
                self.countdown.end(process)  # called off, or a relaunch's plan
            elif tree.details.get(process) != text:
                tree.details[process] = text
                tree.refresh_row(process)
        return bool(self.countdown)


def process_ended(event: ProcessExited, state: str, asked_here: bool) -> tuple[str, str, int]:
    """A process's end as a client shows it: its row's state and its pane's line, in ros2
    launch's words, with its level. The cause came with it, decided where it ended (another
    client's stop, a `tuilaunch stop`, a stop begun before this client attached); this
    client's own asking (`asked_here`) counts too: a crash nobody asked for is failed."""
    asked = asked_here or event.asked
    if event.crashed and not asked and state == "exited":
        state = "failed"
    code = event.code if event.code is not None else 0
    if code == 0:
        return state, f"process has finished cleanly [pid {event.pid}]", INFO
    if event.cause is ExitCause.TYPED:
        return state, (f"process stopped by a key typed into it [pid {event.pid}, "
                       f"{event.reason}]"), INFO
    if asked:
        return state, f"process stopped [pid {event.pid}, {event.reason}]", INFO
    return state, f"process has died [pid {event.pid}, {event.reason}]", ERROR
