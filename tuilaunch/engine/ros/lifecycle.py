"""Following and driving lifecycle nodes: `<node>/get_state`, `change_state`, `transition_event`.

One `LifecycleTracker` per supervisor. When a lifecycle node's process starts, the tracker
subscribes to its `transition_event` topic, asks `get_state` once the service is up (again,
while no answer comes and the process lives), and reports every state as a `lifecycle` event;
with `autostart` it then configures and activates the node. Transition requests (from
`ChangeState` actions or the operator) wait for the node's `change_state` service as long as
its process lives, as launch_ros waits for it; a reply that does not come in time is judged
by the transition events the node published.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from ..describe.lifecycle import STATES, TRANSITIONS, state_keys
from ..errors import LaunchError
from ..plan.model import ActionKind, ActionPlan, ProcessPlan
from ..run.events import LifecycleChanged, Log
from ..run.plugins import ActionRunner, Handlers, Plugin
from ..run.supervisor.supervisor import Supervisor
from ..run.vocabulary.lifecycle import AVAILABLE
from ..run.vocabulary.requests import LifecycleState, Transition
from .actions import RosActions

TRANSITION_IDS = {label: number for number, label in TRANSITIONS.items()}
# the state each transition ends in when the node makes it
GOALS = {"configure": "inactive", "cleanup": "unconfigured", "activate": "active",
         "deactivate": "inactive", "unconfigured_shutdown": "finalized",
         "inactive_shutdown": "finalized", "active_shutdown": "finalized"}
PRIMARY = ("unconfigured", "inactive", "active", "finalized")
ALIVE = ("pending", "running", "respawning")


class LifecycleError(Exception):
    """A transition that could not be asked for or was refused."""


class LifecycleTracker(Plugin):
    """Lifecycle state of each lifecycle process, and the transitions asked of it.

    A supervisor plugin: it follows lifecycle processes as they start and exit, performs
    the plan's `lifecycle_transition` actions, and answers the session requests
    `lifecycle` (a node's state, asked of the node) and `transition` (an operator's)."""

    def __init__(self, supervisor: Supervisor, ros: RosActions) -> None:
        self.supervisor = supervisor
        self.ros = ros
        self.states: dict[str, str] = {}
        self._subscriptions: dict[str, Any] = {}
        self._heard: set[str] = set()  # processes whose transition events arrived
        self._events: dict[str, int] = {}  # transition events heard, per process
        self._goal_seen: dict[tuple[str, str], int] = {}
        """(process, state) -> the count of its transition events when it last reached it."""

    # --- the plugin's hooks ---------------------------------------------------------------

    def actions(self) -> Mapping[str, ActionRunner]:
        return {ActionKind.LIFECYCLE_TRANSITION: self.run_action}

    def process_started(self, proc: ProcessPlan) -> Awaitable[Any] | None:
        return self.follow(proc) if proc.lifecycle else None

    def snapshot(self) -> dict[str, Any]:
        return {"lifecycle": dict(self.states)}

    def handlers(self, find_process: Callable[[str], str]) -> Handlers:
        async def lifecycle(request: LifecycleState, client: int) -> Any:
            return await self.node_state(find_process(request.process))

        async def transition(request: Transition, client: int) -> Any:
            # an operator's transition from an attached TUI; the node's answer and its new
            # state reach every client as lifecycle and log events
            process = find_process(request.process)
            done = await self.request(process, request.transition)
            return {"process": process, "done": done}

        return {LifecycleState: lifecycle, Transition: transition}

    async def node_state(self, process: str) -> dict[str, Any]:
        """The node's own answer to `get_state` (not the state followed here)."""
        from .bridge import RosError

        name = self.supervisor.plan.process(process).full_name
        if not name or "<" in name:
            raise LaunchError(f"{process}: its node name is not known to the launch file")
        try:
            _, response = await self.ros.bridge().call_service(
                f"{name}/get_state", {}, 2.0, service_type="lifecycle_msgs/srv/GetState")
        except RosError as exc:
            return {"process": process, "node": name, "state": None, "error": str(exc)}
        label = (response.get("current_state") or {}).get("label")
        return {"process": process, "node": name, "state": label}

    # --- following -------------------------------------------------------------------------

    async def follow(self, proc: ProcessPlan) -> None:
        """Subscribes to its transitions, reads its state, and autostarts it if asked."""
        name = proc.full_name
        if name is None:
            return
        self.states.pop(proc.id, None)
        self._heard.discard(proc.id)
        try:
            bridge = await self._bridge()
            await self._subscribe(bridge, proc)
            state = await self._first_state(bridge, proc)
        except Exception as exc:  # no ROS or no lifecycle_msgs: say so, go on
            not_started = "; it is not autostarted" if proc.autostart else ""
            self._report(proc.id, f"lifecycle state of {name} unknown: {exc}{not_started}",
                         "WARN")
            return
        if state is None:
            return  # the process ended first
        if proc.id not in self._heard:
            # a transition event that came first is newer than this answer
            self._set_state(proc.id, state)
        if proc.autostart and state == "unconfigured":
            for transition in ("configure", "activate"):
                origin = f"autostart, {proc.origin}" if proc.origin else "autostart"
                if not await self.request(proc.id, transition, origin=origin):
                    return

    async def _bridge(self) -> Any:
        try:
            # on the loop, not in a worker thread: two tasks must never build two bridges
            return self.ros.bridge()
        except Exception as exc:  # rclpy missing or not initialisable
            raise LifecycleError(f"no ROS connection ({exc})") from None

    async def _subscribe(self, bridge: Any, proc: ProcessPlan) -> None:
        try:
            from lifecycle_msgs.msg import TransitionEvent
        except ImportError:
            raise LifecycleError("lifecycle_msgs is not installed") from None
        loop = asyncio.get_running_loop()
        old = self._subscriptions.pop(proc.id, None)
        if old is not None:
            bridge.node.destroy_subscription(old)

        def on_event(msg: Any) -> None:  # in the ROS thread
            loop.call_soon_threadsafe(self._on_transition, proc.id, msg.transition.label,
                                      msg.start_state.label, msg.goal_state.label)

        self._subscriptions[proc.id] = await asyncio.to_thread(
            bridge.node.create_subscription, TransitionEvent,
            f"{proc.full_name}/transition_event", on_event, 10)

    async def _first_state(self, bridge: Any, proc: ProcessPlan) -> str | None:
        from lifecycle_msgs.srv import GetState

        service = f"{proc.full_name}/get_state"
        told = False
        while await self._wait_for_service(bridge, service, proc.id):
            if proc.id in self._heard:  # a transition event said it first
                return self.states.get(proc.id)
            try:
                response = await bridge.call_typed(service, GetState, GetState.Request(),
                                                   self.ros.service_timeout)
            except Exception as exc:
                # On a busy machine a node answers late, or its reply to a client it has not
                # matched yet is dropped. Asking again is harmless; giving up would silently
                # skip its autostart.
                if not told:
                    self._report(proc.id, f"no answer yet from {service} ({exc}): asking "
                                 "again while the node runs", "WARN")
                    told = True
                continue
            return str(response.current_state.label or STATES.get(response.current_state.id))
        return None

    async def _wait_for_service(self, bridge: Any, service: str, proc_id: str) -> bool:
        """Waits while the process lives; False once it is gone or the launch ends."""
        while True:
            if self.supervisor.states.get(proc_id) not in ALIVE:
                return False
            if self.supervisor.shutting_down:
                return False
            try:
                await bridge.wait_for_service(service, 1.0)
                return True
            except Exception:  # not there yet
                continue

    def _on_transition(self, proc_id: str, transition: str, start: str, goal: str) -> None:
        self._heard.add(proc_id)
        self._events[proc_id] = self._events.get(proc_id, 0) + 1
        self._goal_seen[(proc_id, goal)] = self._events[proc_id]
        self._set_state(proc_id, goal, {"transition": transition, "start": start})
        for key in state_keys(transition, start, goal):
            self.supervisor.state_reached(proc_id, "state:" + key)
            self.supervisor.state_reached("*", "state:" + key)

    def _set_state(self, proc_id: str, state: str, detail: dict[str, str] | None = None)\
            -> None:
        if self.states.get(proc_id) == state and detail is None:
            return
        self.states[proc_id] = state
        data = {"state": state, **(detail or {})}
        self.supervisor.emit(LifecycleChanged(proc_id, reason=state, data=data))

    def _report(self, item: str, text: str, level: str = "INFO") -> None:
        self.supervisor.emit(Log(item, reason=text, level=level))

    def process_exited(self, proc_id: str) -> None:
        """A node that is gone has no lifecycle state any more."""
        sub = self._subscriptions.pop(proc_id, None)
        if sub is not None and self.ros.made is not None:
            try:
                self.ros.made.node.destroy_subscription(sub)
            except Exception:  # the bridge is closing
                pass
        if self.states.pop(proc_id, None) is not None:
                self.supervisor.emit(LifecycleChanged(proc_id, reason="",
                                        data={"state": ""}))

    # --- driving ---------------------------------------------------------------------------

    async def request(self, proc_id: str, transition: str | int, origin: str = "operator",
                      report_to: str | None = None) -> bool:
        """Asks a lifecycle process for one transition; True when the node made it."""
        label = TRANSITIONS.get(transition, str(transition)) if isinstance(transition, int) \
            else transition
        where = report_to or proc_id
        proc = self.supervisor.plan.process(proc_id)
        if not proc.lifecycle or proc.full_name is None:
            self._report(where, f"{proc_id} is not a lifecycle node", "ERROR")
            return False
        if label not in TRANSITION_IDS:
            self._report(where, f"'{label}' is not a lifecycle transition "
                         f"({', '.join(TRANSITION_IDS)})", "ERROR")
            return False
        state = self.states.get(proc_id)
        if origin == "operator" and state in AVAILABLE and label not in AVAILABLE[state]:
            # asked of the node anyway, an rclpy lifecycle node dies of it: say no here
            self._report(where, f"cannot {label} {proc.full_name}: it is {state} (it can "
                         f"{', '.join(AVAILABLE[state])})", "ERROR")
            return False
        try:
            from lifecycle_msgs.srv import ChangeState
        except ImportError:
            self._report(where, "lifecycle_msgs is not installed: cannot change the state of "
                         f"{proc.full_name}", "ERROR")
            return False
        try:
            bridge = await self._bridge()
        except LifecycleError as exc:
            self._report(where, f"{label} {proc.full_name} failed: {exc}", "ERROR")
            return False
        service = f"{proc.full_name}/change_state"
        if not await self._wait_for_service(bridge, service, proc_id):
            self._report(where, f"{label} {proc.full_name} abandoned: the node is not "
                         "running", "WARN")
            return False
        request = ChangeState.Request()
        request.transition.id = TRANSITION_IDS[label]
        before = self._events.get(proc_id, 0)
        try:
            response = await bridge.call_typed(service, ChangeState, request,
                                               self.ros.service_timeout)
            success = bool(response.success)
        except Exception as exc:
            # A transition longer than the timeout, or a reply lost on a busy machine: the
            # node's transition events tell how it ended. Asking again could repeat it.
            outcome = await self._outcome(proc_id, label, before)
            if outcome is None:
                self._report(where, f"{label} {proc.full_name} failed: {exc}", "ERROR")
                return False
            self._report(where, f"{label} {proc.full_name}: {exc}; its transition events "
                         f"tell the outcome", "WARN")
            success = outcome
        if not success:
            state = await self._settled(proc_id)
            self._report(where, f"{proc.full_name} refused transition '{label}' ({origin}); "
                         f"it is {state or 'in an unknown state'}", "ERROR")
            return False
        # the reply can come before the transition event that says the new state (a busy
        # machine): answered once the state is known, so a step asked next (`]]`) is asked
        # of the state it follows, not refused as asked of the one before
        await self._reached(proc_id, GOALS.get(label), before)
        self._report(where, f"{proc.full_name}: {label} done ({origin})")
        return True

    async def _reached(self, proc_id: str, goal: str | None, before: int,
                       patience: float = 5.0) -> None:
        """Until the node's transition events say it reached `goal` since the `before`-th
        (at most `patience` seconds, and only for a node whose events are heard). Reached,
        not is in: a handler on that state may have moved it on already (inactive, then
        active at once)."""
        deadline = time.monotonic() + patience
        while goal is not None and proc_id in self._heard \
                and self._goal_seen.get((proc_id, goal), 0) <= before \
                and self.supervisor.states.get(proc_id) in ALIVE \
                and not self.supervisor.shutting_down and time.monotonic() < deadline:
            await asyncio.sleep(0.05)  # its transition event ends the wait

    async def _settled(self, proc_id: str, patience: float | None = 5.0) -> str | None:
        """The node's state once the transition it is in is over (at most `patience`
        seconds; None: as long as it lives). A refusal's reply can come before the
        transition event that takes the node back from `configuring` (a busy machine): the
        state said is the one it is left in, not the one it passed through."""
        deadline = None if patience is None else time.monotonic() + patience
        while self.states.get(proc_id) not in (None, *PRIMARY) \
                and self.supervisor.states.get(proc_id) in ALIVE \
                and not self.supervisor.shutting_down \
                and (deadline is None or time.monotonic() < deadline):
            await asyncio.sleep(0.05)  # its transition event ends the wait
        return self.states.get(proc_id)

    async def _outcome(self, proc_id: str, label: str, before: int) -> bool | None:
        """Whether the node made `label`, from the transition events heard since `before`
        events: None when it never began the transition or is gone before ending it."""
        if self._events.get(proc_id, 0) <= before:
            return None
        state = await self._settled(proc_id, patience=None)
        return state == GOALS.get(label) if state in PRIMARY else None

    async def run_action(self, action: ActionPlan) -> bool:
        """A `ChangeState` / `LifecycleTransition` of the launch file, for each target."""
        targets: list[str] = action.data.get("targets", [])
        if not targets:
            self._report(action.id, f"{'+'.join(action.data.get('transitions', []))} "
                         f"{action.target}: no lifecycle node of this launch matches", "WARN")
            return False
        results = await asyncio.gather(*(self._transitions(action, pid) for pid in targets))
        return all(results)

    async def _transitions(self, action: ActionPlan, proc_id: str) -> bool:
        for label in action.data.get("transitions", []):
            if not await self.request(proc_id, label, origin=f"{action.origin or action.id}",
                                      report_to=action.id):
                return False
        return True


__all__ = ["LifecycleTracker"]
