"""When things happen: the book of what has happened and of who waits for what.

`TriggerBook` owns the trigger state of a run: the flags a start-up chain waits on (a
process's start or exit, a lifecycle state), the count of lifecycle transitions an
OnStateTransition re-runs on, and the event handlers filed by event (output, shutdown, any
process's start or exit). It answers whether a trigger can still fire; the supervisor does
the waiting and the performing (run/supervisor/plan_actions.py). It is made and read alone:
tests/integration/test_supervisor_parts.py.
"""

from __future__ import annotations

import asyncio
from collections.abc import Iterable, Mapping
from typing import Any, Literal

from ...describe.entities import TriggerOn
from ...plan.model import ActionPlan, ProcessPlan, Trigger

Filing = Literal["handler", "every_state", "chain"]
EVERY_PROCESS = (TriggerOn.START, TriggerOn.EXIT, TriggerOn.IO)
"""The kinds of handler that, without a target, fire for every process's event."""
"""How an action waits: filed as an event handler, re-run on every lifecycle transition,
or performed once its start-up chain has happened."""


class TriggerBook:
    """What has happened (flags, transitions) and the event handlers, by event."""

    def __init__(self) -> None:
        self.happened: dict[tuple[str, str], asyncio.Event] = {}
        """Set when (process, event kind) has happened: what triggers wait on."""
        self.occurrences: dict[tuple[str, str], int] = {}
        """Lifecycle transitions seen per (node or "*", state filter)."""
        self.pulses: dict[tuple[str, str], asyncio.Event] = {}
        """Pulsed at each such transition: what re-runs an OnStateTransition's actions."""
        self.io_watchers: dict[tuple[str, str], list[ActionPlan]] = {}
        """Event handlers on a process's output, by (process, stream)."""
        self.on_shutdown: list[ActionPlan] = []
        """OnShutdown handlers, run once when the launch begins to stop."""
        self.any_watchers: dict[str, list[ActionPlan]] = {}
        """Event handlers without a target (any process), by event kind."""

    def flag(self, process_id: str, what: str) -> asyncio.Event:
        return self.happened.setdefault((process_id, what), asyncio.Event())

    def state_reached(self, process_id: str, what: str) -> None:
        """A lifecycle transition matching `what`: once for start-up chains, and counted
        for the handlers that run on each match."""
        key = (process_id, what)
        self.flag(process_id, what).set()
        self.occurrences[key] = self.occurrences.get(key, 0) + 1
        pulse = self.pulses.pop(key, None)
        if pulse is not None:
            pulse.set()

    def transitions(self, key: tuple[str, str]) -> int:
        """How many matching lifecycle transitions were seen so far."""
        return self.occurrences.get(key, 0)

    async def next_transition(self, key: tuple[str, str], seen: int) -> None:
        """Returns once more than `seen` matching transitions were seen."""
        while self.occurrences.get(key, 0) <= seen:
            await self.pulses.setdefault(key, asyncio.Event()).wait()

    def file(self, action: ActionPlan) -> Filing:
        """Files an event handler under its event; says how any other action waits."""
        chain = action.trigger
        while chain is not None and chain.on not in (TriggerOn.IO, TriggerOn.SHUTDOWN):
            chain = chain.after
        first = action.trigger
        if chain is not None and chain.on == TriggerOn.SHUTDOWN:
            self.on_shutdown.append(action)
        elif first is not None and first.target is None and first.on in EVERY_PROCESS:
            # a handler without target_action: every process's event runs it
            kind = f"io:{first.io or 'stdout'}" if first.on == TriggerOn.IO else first.on
            self.any_watchers.setdefault(kind, []).append(action)
        elif chain is not None and chain.target is not None:
            key = (chain.target, chain.io or "stdout")
            self.io_watchers.setdefault(key, []).append(action)
        elif first is not None and first.on == TriggerOn.STATE and first.repeat and \
                first.target is not None:
            return "every_state"
        else:
            return "chain"
        return "handler"

    def forget_handlers(self) -> None:
        """A new plan files its handlers again (what has happened stays)."""
        self.io_watchers.clear()
        self.on_shutdown.clear()
        self.any_watchers.clear()

    @property
    def watches_output(self) -> bool:
        """Whether any handler waits on output: else a line costs no look-up."""
        return bool(self.io_watchers or self.any_watchers)

    def handlers_of(self, on: str) -> list[ActionPlan]:
        """The handlers of every process's `on` ("start", "exit")."""
        return self.any_watchers.get(on, [])

    def output_handlers(self, process_id: str, stream: str) -> list[ActionPlan]:
        return [*self.io_watchers.get((process_id, stream), []),
                *self.any_watchers.get(f"io:{stream}", [])]

    def can_fire(self, trigger: Trigger | None, states: Mapping[str, str],
                 processes: Iterable[ProcessPlan]) -> bool:
        """Whether what `trigger` waits for has happened or is alive or pending."""
        while trigger is not None:
            if trigger.target == "*" and trigger.on == TriggerOn.STATE:
                # any lifecycle node of the launch: one of them must still be able to run
                if not self.flag("*", flag_name(trigger)).is_set() and not any(
                        p.lifecycle and states.get(p.id) in ("running", "pending")
                        for p in processes):
                    return False
            if trigger.target not in (None, "*") and trigger.on in (
                    TriggerOn.START, TriggerOn.EXIT, TriggerOn.STATE):
                assert trigger.target is not None
                done = self.flag(trigger.target, flag_name(trigger)).is_set()
                if not done and states.get(trigger.target) not in ("running", "pending"):
                    return False
            trigger = trigger.after
        return True

    def action_can_fire(self, action: ActionPlan, states: Mapping[str, str],
                        processes: Iterable[ProcessPlan]) -> bool:
        """Whether a pending action may still run before the launch goes idle."""
        trigger = action.trigger
        if trigger is not None and trigger.target is None and trigger.on in EVERY_PROCESS:
            return False  # runs per event; it never holds the launch open by itself
        chain = trigger
        while chain is not None:
            if chain.on == TriggerOn.SHUTDOWN:
                return False
            if chain.on == TriggerOn.IO and chain.target is not None and \
                    states.get(chain.target) not in ("running", "pending"):
                return False
            chain = chain.after
        return self.can_fire(trigger, states, processes)

    def due_in_shutdown(self, actions: Iterable[ActionPlan], states: Mapping[str, str],
                        detached: set[str]) -> bool:
        """Exit handlers whose process has just stopped, or that are still running."""
        for action in actions:
            state = states.get(action.id)
            if state == "running" and action.kind not in detached:
                return True
            if state == "pending" and action.enabled and action.trigger is None:
                return True  # performed by a handler just now, about to run
            if state == "pending" and action.enabled and action.trigger is not None:
                step: Trigger | None = action.trigger
                due = True
                while step is not None and due:
                    due = (step.on == TriggerOn.EXIT and not step.delay and step.target is not None
                           and self.flag(step.target, "exit").is_set())
                    step = step.after
                if due:
                    return True
        return False


def runs_in_shutdown(step: Trigger, item: Any) -> bool:
    """Exit handlers run while launch shuts down (their process stopped because of it)."""
    return isinstance(item, ActionPlan) and step.on == TriggerOn.EXIT and not step.delay


def flag_name(trigger: Trigger) -> str:
    """A lifecycle state trigger waits for its own filter, other triggers for the event."""
    return f"state:{trigger.io}" if trigger.on == TriggerOn.STATE else trigger.on
