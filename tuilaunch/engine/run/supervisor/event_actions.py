"""Perform launch entities when an event happens: the event-time half of the Plan.

What an event handler, a timer or OnShutdown holds and could not be described ahead (an
OpaqueFunction, a branch whose substitutions fail until then, the body of a handler that
applies to every process, the entities a callback returns) is resolved here, with the scope
it was written in and the event as `context.locals.event`. The new processes and actions
join the running Plan; the supervisor starts them.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from typing import Any

from ...describe.python.launch_events import EventInfo
from ...plan.model import ActionPlan, Plan, ProcessPlan, TreeItem
from ...plan.resolve import Deferred, Resolver, Scope


@dataclass
class Performed:
    """What performing entities added to the plan."""

    processes: list[ProcessPlan]
    actions: list[ActionPlan]
    warnings: list[str]


def _tree_item(plan: Plan, ref: str) -> TreeItem | None:
    stack = [plan.tree]
    while stack:
        item = stack.pop()
        if item.ref == ref:
            return item
        stack.extend(item.children)
    return None


def scope_of(plan: Plan, action: ActionPlan) -> Scope:
    """The scope an action was written in: captured for deferred ones, rebuilt otherwise.
    Its environment is the launch's at this moment (launch's context.environment is
    os.environ when the event happens), not the one of the scope it was written in."""
    if isinstance(action.source, Deferred):
        scope = action.source.scope.child(False)
    else:
        launch_file = action.origin.file if action.origin else plan.file
        scope = Scope(dict(action.configurations), os.path.abspath(launch_file),
                      action.namespace)
    return replace(scope, trigger=None, enabled=True, skipped_by=None, env=dict(plan.environ))


def perform_entities(plan: Plan, action: ActionPlan, entities: list[Any],
                     event: EventInfo | None) -> Performed:
    """Resolves entities now, as children of `action`, and adds them to the plan.

    Raises LaunchError when an entity cannot be performed: the caller reports it for this
    action only."""
    scope = scope_of(plan, action)
    scope.event_locals = {"event": event} if event is not None else {}
    resolver = Resolver(scope.configurations, plan.params_dir, entity_ids=plan.entity_ids,
                        counter=plan.id_counter, action_offset=len(plan.actions))
    parent = _tree_item(plan, action.id) or plan.tree
    resolver.walk(entities, scope, parent)
    plan.environ = dict(scope.env)  # launch's os.environ keeps what they changed
    resolver.link_triggers()
    plan.id_counter = resolver.id_counter
    plan.processes.extend(resolver.processes)
    plan.actions.extend(resolver.actions)
    return Performed(resolver.processes, resolver.actions, resolver.warnings)


def deferred_entities(action: ActionPlan) -> list[Any]:
    return list(action.source.entities) if isinstance(action.source, Deferred) else []
