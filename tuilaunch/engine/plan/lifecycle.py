"""Lifecycle transitions in a plan: which nodes each request targets, and state triggers.

A `ChangeState` matcher may name a node declared later in the file, so targets are bound
once the whole launch has been walked. A matcher that is a plain function is called with each
LifecycleNode action, its `node_name` set to the full name, as launch_ros calls it.
"""

from __future__ import annotations

from typing import Any

from ..describe.lifecycle import (
    TRANSITIONS,
    ChangeStateAction,
    LifecycleTransition,
    OnStateTransition,
    describe_matcher,
    state_filter,
)
from ..describe.substitutions import PerformContext, perform, perform_optional
from ..errors import LaunchError
from .model import ActionKind, ActionPlan, ProcessPlan, TreeItem


def transition_ids(values: list[Any], ctx: PerformContext, where: Any) -> list[int]:
    ids: list[int] = []
    for value in values:
        text = value if isinstance(value, int) else perform(value, ctx)
        try:
            number = int(text)
        except (TypeError, ValueError):
            raise LaunchError(f"lifecycle transition {text!r} is not a transition id",
                              where) from None
        if number not in TRANSITIONS:
            raise LaunchError(f"lifecycle transition id {number} is not one of "
                              f"{sorted(TRANSITIONS)}", where)
        ids.append(number)
    return ids


def transition_action(entity: ChangeStateAction | LifecycleTransition, ctx: PerformContext)\
        -> tuple[str, dict[str, Any]]:
    """The target text and data of a lifecycle_transition ActionPlan (targets bound later)."""
    if isinstance(entity, ChangeStateAction):
        ids = [entity.transition_id]
        target = describe_matcher(entity.matcher)
        names: list[str] = []
    else:
        ids = transition_ids(entity.transition_ids, ctx, entity.origin)
        names = ["/" + n.lstrip("/") for n in (perform(v, ctx) for v in entity.node_names)]
        target = ", ".join(names)
    return target, {"transitions": [TRANSITIONS[i] for i in ids], "transition_ids": ids,
                    "node_names": names, "targets": []}


def bind_targets(processes: list[ProcessPlan], actions: list[ActionPlan],
                 entities: dict[str, Any], tree: TreeItem) -> list[str]:
    """Fills each transition's `targets` (process ids) and names them in the tree.

    Returns a warning for each transition that matches no lifecycle node."""
    lifecycle = [p for p in processes if p.lifecycle and p.enabled]
    warnings: list[str] = []
    for action in actions:
        if action.kind != ActionKind.LIFECYCLE_TRANSITION:
            continue
        source = action.source
        targets: list[str] = []
        if isinstance(source, ChangeStateAction):
            matcher = source.matcher
            targets = [p.id for p in lifecycle if p.id in entities
                       and _matches(matcher, entities[p.id], p)]
        else:
            wanted = set(action.data["node_names"])
            targets = [p.id for p in lifecycle if p.full_name in wanted]
        action.data["targets"] = targets
        if targets:
            action.target = ", ".join(p.full_name or p.id for p in lifecycle
                                      if p.id in targets)
            _relabel(tree, action.id, f"{'+'.join(action.data['transitions'])} "
                     f"{action.target}")
        if action.enabled and not targets:
            warnings.append(f"{action.origin}: {action.data['transitions'][0]} request for "
                            f"{action.target} matches no lifecycle node of this launch")
    return warnings


def _relabel(item: TreeItem, ref: str, label: str) -> None:
    for child in item.children:
        if child.ref == ref:
            child.label = label
        _relabel(child, ref, label)


def _matches(matcher: Any, entity: Any, proc: ProcessPlan) -> bool:
    # launch_ros's LifecycleNode knows its full name once executed; so does this one now
    try:
        entity.node_name = proc.full_name or ""
    except AttributeError:  # a read-only node_name that already says it
        pass
    try:
        return bool(matcher(entity))
    except Exception:  # a user's matcher that expects more than a name: not this node
        return False


def state_trigger_io(handler: OnStateTransition, ctx: PerformContext) -> str:
    """The `transition|start|goal` filter an OnStateTransition waits for."""
    return state_filter(perform_optional(handler.transition, ctx),
                        perform_optional(handler.start_state, ctx),
                        perform_optional(handler.goal_state, ctx))


__all__ = ["bind_targets", "state_trigger_io", "transition_action"]
