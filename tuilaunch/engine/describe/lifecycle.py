"""Lifecycle nodes as a launch file describes them (launch_ros's lifecycle API).

`LifecycleNode` is a `Node` whose state the supervisor follows; `EmitEvent(ChangeState(...))`
becomes a `ChangeStateAction` that asks the matching lifecycle nodes for a transition;
`OnStateTransition` starts its entities when a node reaches a state. Matchers stay plain
objects so that a plan can say which node they target without running anything.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from ..errors import DslError, caller_origin
from .conditions import Condition
from .entities import EMITTED_EVENTS, Entity, EventHandler, Node, TriggerOn
from .substitutions import SubValue

# lifecycle_msgs/msg/Transition ids and lifecycle_msgs/msg/State ids, as in the message
# definitions: a file passes the numbers, the UI shows the labels
TRANSITIONS: dict[int, str] = {
    0: "create", 1: "configure", 2: "cleanup", 3: "activate", 4: "deactivate",
    5: "unconfigured_shutdown", 6: "inactive_shutdown", 7: "active_shutdown", 8: "destroy",
}
# the transition's label as rcl_lifecycle publishes it on transition_event
TRANSITION_LABELS: dict[int, str] = {
    1: "configure", 2: "cleanup", 3: "activate", 4: "deactivate", 5: "shutdown",
    6: "shutdown", 7: "shutdown", 8: "destroy", 0: "create",
}
STATES: dict[int, str] = {
    0: "unknown", 1: "unconfigured", 2: "inactive", 3: "active", 4: "finalized",
    10: "configuring", 11: "cleaningup", 12: "shuttingdown", 13: "activating",
    14: "deactivating", 15: "errorprocessing",
}


class LifecycleNode(Node):
    """launch_ros.actions.LifecycleNode; `autostart=True` configures then activates it."""

    kind = "node"

    def __init__(self, *, name: SubValue = None, namespace: SubValue = None,
                 autostart: Any = False, **kwargs: Any) -> None:
        super().__init__(name=name, namespace=namespace, **kwargs)
        self.origin = caller_origin()
        if self.name is None:
            raise DslError("LifecycleNode() needs a name: its change_state service and "
                           "transition_event topic are found by it", self.origin)
        self.autostart = autostart
        self.lifecycle = True

    def describe(self) -> str:
        return "lifecycle " + super().describe()


class NodeMatcher:
    """A `lifecycle_node_matcher` the plan can read: by action, or by full node name."""

    def __init__(self, *, action: Any = None, node_name: str | None = None,
                 function: Callable[[Any], bool] | None = None) -> None:
        self.action = action
        self.node_name = node_name
        self.function = function

    def __call__(self, node: Any) -> bool:
        if self.action is not None:
            return node is self.action
        if self.node_name is not None:
            return getattr(node, "node_name", None) == self.node_name
        return self.function is not None and bool(self.function(node))

    def describe(self) -> str:
        if self.action is not None:
            return self.action.describe() if hasattr(self.action, "describe") else "an action"
        return self.node_name or "nodes matched by a function"


def matches_node_name(node_name: str) -> NodeMatcher:
    """launch_ros.events.matches_node_name: by full node name (`/` prepended if missing)."""
    if not node_name.startswith("/"):
        node_name = "/" + node_name
    return NodeMatcher(node_name=node_name)


class ChangeState:
    """launch_ros.events.lifecycle.ChangeState: a transition request for matching nodes."""

    name = "launch_ros.events.lifecycle.ChangeState"
    valid_transitions = {i: f"TRANSITION_{label.upper()}" for i, label in TRANSITIONS.items()}
    valid_states = {i: f"PRIMARY_STATE_{label.upper()}" if i < 10 else
                    f"TRANSITION_STATE_{label.upper()}" for i, label in STATES.items()}

    def __init__(self, *, lifecycle_node_matcher: Callable[[Any], bool],
                 transition_id: int) -> None:
        self.origin = caller_origin()
        if transition_id not in TRANSITIONS:
            raise DslError(f"ChangeState(transition_id={transition_id!r}) is not a lifecycle "
                           "transition id", self.origin,
                           hint="use lifecycle_msgs.msg.Transition.TRANSITION_CONFIGURE, ...")
        if not callable(lifecycle_node_matcher):
            raise DslError("ChangeState(lifecycle_node_matcher=...) must be callable, e.g. "
                           "matches_action(node)", self.origin)
        self.lifecycle_node_matcher = lifecycle_node_matcher
        self.transition_id = transition_id

    def as_action(self, condition: Condition | None) -> ChangeStateAction:
        """What `EmitEvent(event=ChangeState(...))` stands for in a Description."""
        action = ChangeStateAction(self.lifecycle_node_matcher, self.transition_id, condition)
        action.origin = caller_origin() or self.origin
        return action


class ChangeStateAction(Entity):
    """Asks every matching lifecycle node of the launch for one transition."""

    def __init__(self, matcher: Callable[[Any], bool], transition_id: int,
                 condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.matcher = matcher
        self.transition_id = transition_id

    def describe(self) -> str:
        return f"{TRANSITIONS[self.transition_id]} {describe_matcher(self.matcher)}"


def describe_matcher(matcher: Any) -> str:
    if isinstance(matcher, NodeMatcher):
        return matcher.describe()
    target = getattr(matcher, "target", None)  # launch.events.matches_action(node)
    if target is not None and hasattr(target, "describe"):
        return str(target.describe())
    return "nodes matched by a function"


class LifecycleTransition(Entity):
    """launch_ros.actions.LifecycleTransition: transitions for nodes named by full name."""

    def __init__(self, *, lifecycle_node_names: Iterable[SubValue],
                 transition_ids: Iterable[Any], condition: Condition | None = None,
                 **_: Any) -> None:
        self._init_entity(condition)
        self.node_names = list(lifecycle_node_names)
        self.transition_ids = list(transition_ids)


class StateTransition:
    """launch_ros.events.lifecycle.StateTransition, as event callbacks receive it."""

    name = "launch_ros.events.lifecycle.StateTransition"

    def __init__(self, *, action: Any, msg: Any) -> None:
        self.action = action
        self.msg = msg
        self.timestamp = getattr(msg, "timestamp", 0)
        self.transition = msg.transition.label
        self.start_state = msg.start_state.label
        self.goal_state = msg.goal_state.label


class OnStateTransition(EventHandler):
    """launch_ros.event_handlers.OnStateTransition: entities run when a node changes state."""

    on = TriggerOn.STATE

    def __init__(self, *, entities: Any = None, target_lifecycle_node: Any = None,
                 transition: SubValue = None, start_state: SubValue = None,
                 goal_state: SubValue = None, matcher: Callable[[Any], bool] | None = None,
                 **kwargs: Any) -> None:
        if target_lifecycle_node is not None and not isinstance(target_lifecycle_node,
                                                                LifecycleNode):
            raise DslError("OnStateTransition requires a 'LifecycleNode' action as the target",
                           caller_origin())
        super().__init__(target_lifecycle_node, entities if entities is not None
                         else kwargs.get("on_state_transition"))
        self.transition = transition
        self.start_state = start_state
        self.goal_state = goal_state
        self.matcher = matcher
        # launch_ros runs the entities on every matching transition unless told once
        self.handle_once = bool(kwargs.get("handle_once", False))


def state_filter(transition: str | None, start_state: str | None, goal_state: str | None)\
        -> str:
    """The key a state trigger waits on: `transition|start|goal`, `*` for any."""
    return "|".join(part or "*" for part in (transition, start_state, goal_state))


def state_keys(transition: str, start_state: str, goal_state: str) -> list[str]:
    """Every key a transition event satisfies (each part given or left open)."""
    keys = []
    for t in (transition, None):
        for s in (start_state, None):
            for g in (goal_state, None):
                keys.append(state_filter(t, s, g))
    # an empty label (rcl's intermediate transitions have none) reads as "any": each key once
    return list(dict.fromkeys(keys))


# EmitEvent(event=ChangeState(...)) stands for a ChangeStateAction in a Description
EMITTED_EVENTS[ChangeState] = lambda event, condition: event.as_action(condition)

__all__ = [
    "ChangeState",
    "ChangeStateAction",
    "LifecycleNode",
    "LifecycleTransition",
    "NodeMatcher",
    "OnStateTransition",
    "StateTransition",
    "matches_node_name",
]
