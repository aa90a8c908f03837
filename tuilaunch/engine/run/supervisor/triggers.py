"""When things happen: start-up chains (`when ready`), event watchers, lifecycle states.

A process or action with a trigger waits for its target's start, exit or lifecycle state
(and delay); handlers on output or shutdown are run by their events; an OnStateTransition
re-runs on every matching transition. `state_reached` is how a plugin (the lifecycle
tracker) reports a state.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from ...plan.model import ActionPlan, Trigger
from .core import SupervisorCore


class Triggers(SupervisorCore):
    """Waiting for triggers and dispatching event handlers."""

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

    async def _on_every_state(self, action: ActionPlan) -> None:
        """launch_ros's OnStateTransition: the entities run on the first matching
        transition and again on each later one (a node cycled by the operator or a
        manager), until shutdown."""
        trigger = action.trigger
        assert trigger is not None and trigger.target is not None
        key = (trigger.target, flag_name(trigger))
        await self.when_ready(trigger, self.perform_action, action)
        seen = self.occurrences.get(key, 0)
        while not self.shutting_down:
            while self.occurrences.get(key, 0) <= seen:
                await self.pulses.setdefault(key, asyncio.Event()).wait()
            seen += 1
            if self.shutting_down or not action.enabled:
                return
            if trigger.delay:
                await asyncio.sleep(trigger.delay)
            await self.perform_action(action)

    def can_fire(self, trigger: Trigger | None) -> bool:
        while trigger is not None:
            if trigger.target == "*" and trigger.on == "state":
                # any lifecycle node of the launch: one of them must still be able to run
                if not self.flag("*", flag_name(trigger)).is_set() and not any(
                        p.lifecycle and self.states.get(p.id) in ("running", "pending")
                        for p in self.plan.processes):
                    return False
            if trigger.target not in (None, "*") and trigger.on in ("start", "exit", "state"):
                assert trigger.target is not None
                done = self.flag(trigger.target, flag_name(trigger)).is_set()
                if not done and self.states.get(trigger.target) not in ("running", "pending"):
                    return False
            trigger = trigger.after
        return True

    async def when_ready(self, trigger: Trigger | None, then: Callable[[Any], Any],
                         item: Any) -> None:
        chain: list[Trigger] = []
        while trigger is not None:
            chain.insert(0, trigger)
            trigger = trigger.after
        for step in chain:
            if step.on == "shutdown" or step.on == "io":
                return  # run by their own events, not as a start-up chain
            if step.target is not None:
                await self.flag(step.target, flag_name(step)).wait()
            if step.delay:
                self.busy += 1
                try:
                    await asyncio.sleep(step.delay)
                finally:
                    self.busy -= 1
                    self.changed.set()
            if self.shutting_down and not runs_in_shutdown(step, item):
                return
        result = then(item)
        if asyncio.iscoroutine(result):
            await result

    def schedule_action(self, action: ActionPlan) -> None:
        chain = action.trigger
        while chain is not None and chain.on not in ("io", "shutdown"):
            chain = chain.after
        first = action.trigger
        if chain is not None and chain.on == "shutdown":
            self.on_shutdown.append(action)
        elif first is not None and first.target is None and first.on in ("start", "exit", "io"):
            # a handler without target_action: every process's event runs it
            kind = f"io:{first.io or 'stdout'}" if first.on == "io" else first.on
            self.any_watchers.setdefault(kind, []).append(action)
        elif chain is not None and chain.target is not None:
            key = (chain.target, chain.io or "stdout")
            self.io_watchers.setdefault(key, []).append(action)
        elif first is not None and first.on == "state" and first.repeat and \
                first.target is not None:
            self.spawn_task(self._on_every_state(action))
        else:
            self.spawn_task(self.when_ready(action.trigger, self.perform_action, action))

    def action_can_fire(self, action: ActionPlan) -> bool:
        """Whether a pending action may still run before the launch goes idle."""
        trigger = action.trigger
        if trigger is not None and trigger.target is None and trigger.on in ("start", "exit",
                                                                              "io"):
            return False  # runs per event; it never holds the launch open by itself
        chain = trigger
        while chain is not None:
            if chain.on == "shutdown":
                return False
            if chain.on == "io" and chain.target is not None and \
                    self.states.get(chain.target) not in ("running", "pending"):
                return False
            chain = chain.after
        return self.can_fire(trigger)

    def actions_due_in_shutdown(self) -> bool:
        """Exit handlers whose process has just stopped, or that are still running."""
        for action in self.plan.actions:
            state = self.states.get(action.id)
            if state == "running" and action.kind not in self.detached_actions:
                return True
            if state == "pending" and action.enabled and action.trigger is None:
                return True  # performed by a handler just now, about to run
            if state == "pending" and action.enabled and action.trigger is not None:
                step: Trigger | None = action.trigger
                due = True
                while step is not None and due:
                    due = (step.on == "exit" and not step.delay and step.target is not None
                           and self.flag(step.target, "exit").is_set())
                    step = step.after
                if due:
                    return True
        return False


def runs_in_shutdown(step: Trigger, item: Any) -> bool:
    """Exit handlers run while launch shuts down (their process stopped because of it)."""
    return isinstance(item, ActionPlan) and step.on == "exit" and not step.delay


def flag_name(trigger: Trigger) -> str:
    """A lifecycle state trigger waits for its own filter, other triggers for the event."""
    return f"state:{trigger.io}" if trigger.on == "state" else trigger.on
