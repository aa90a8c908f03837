"""What a non-process action does once planned: log, call_service, set_parameters, shutdown,
stop_process, signal_process, coroutine, load_components, lifecycle transitions and event
callbacks."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..describe.conditions import ConditionOutcome
from ..describe.entities import (
    CallService,
    LoadComposableNodes,
    LogInfo,
    Node,
    OpaqueCoroutine,
    SendSignal,
    SetParameters,
    Shutdown,
    StopProcess,
)
from ..describe.lifecycle import ChangeStateAction, LifecycleTransition
from ..describe.substitutions import PerformContext, describe, perform, perform_optional
from ..describe.values import flatten_parameters, typed_value
from ..errors import Origin
from . import lifecycle as lifecycle_plan
from .components import component_plan
from .model import ActionKind, ActionPlan, ProcessPlan
from .scope import Scope, join_namespace, resolve_name


class ActionPlanner:
    """Plans actions for one Resolver: `action_id` numbers them, `entity_ids` and `processes`
    are the plan's so far (a StopProcess or a container names one of them)."""

    def __init__(self, action_id: Callable[[str], str], entity_ids: dict[int, str],
                 processes: list[ProcessPlan]) -> None:
        self.action_id = action_id
        self.entity_ids = entity_ids
        self.processes = processes

    def plan(self, entity: Any, scope: Scope, enabled: bool,
             skipped: ConditionOutcome | None) -> tuple[ActionPlan, str]:
        """The action's plan, and its label in the launch tree."""
        ctx = scope.context()
        target: str | None = None
        data: Any = None
        verbosity = ""
        if isinstance(entity, LogInfo):
            kind = ActionKind.LOG
            data = perform(entity.msg, ctx) if enabled else describe(entity.msg)
        elif isinstance(entity, CallService):
            kind = ActionKind.CALL_SERVICE
            if enabled:
                target = resolve_name(scope.namespace, perform(entity.server, ctx))
                data = request_values(entity.request, ctx, scope.namespace, entity.origin)
                verbosity = perform(entity.verbosity, ctx)
            else:
                target = describe(entity.server)
        elif isinstance(entity, SetParameters):
            kind = ActionKind.SET_PARAMETERS
            if enabled:
                target = resolve_name(scope.namespace, perform(entity.node_name, ctx))
                data = flatten_parameters(entity.parameters, ctx, entity.origin)
                verbosity = perform(entity.verbosity, ctx)
            else:
                target = describe(entity.node_name)
        elif isinstance(entity, Shutdown):
            kind = ActionKind.SHUTDOWN
            data = perform(entity.reason, ctx) if enabled else describe(entity.reason)
        elif isinstance(entity, StopProcess | SendSignal):
            # the process `matches_action(x)` names: its id, once x is in the plan
            kind = ActionKind.STOP_PROCESS if isinstance(entity, StopProcess) \
                else ActionKind.SIGNAL_PROCESS
            target = self.entity_ids.get(id(entity.target)) or describe_entity(entity.target)
            data = getattr(entity, "signal_name", None)
        elif isinstance(entity, OpaqueCoroutine):
            kind = ActionKind.COROUTINE
            data = entity.name
        elif isinstance(entity, LoadComposableNodes):
            kind = ActionKind.LOAD_COMPONENTS
            target, data = self.load_components(entity, scope, enabled)
        elif isinstance(entity, ChangeStateAction | LifecycleTransition):
            kind = ActionKind.LIFECYCLE_TRANSITION
            target, data = lifecycle_plan.transition_action(entity, ctx) if enabled else (
                describe(getattr(entity, "node_names", "lifecycle nodes")),
                {"transitions": [], "transition_ids": [], "node_names": [], "targets": []})
        else:
            kind = ActionKind.EVENT_CALLBACK
            data = len(entity.callbacks)
        action_id = self.action_id(kind)
        plan = ActionPlan(action_id, kind, target, data, scope.namespace, verbosity, enabled,
                          skipped, scope.trigger, entity.origin, entity,
                          dict(scope.configurations), dict(scope.env), scope.launch_file)
        label = {"log": f"log: {data}", "call_service": f"call {target}",
                 "set_parameters": f"set parameters of {target}",
                 "shutdown": "shutdown", "event_callback": "event callback",
                 "stop_process": f"stop {target}",
                 "signal_process": f"signal {data} to {target}",
                 "coroutine": f"coroutine {data}",
                 "load_components": f"load components into {target}",
                 "lifecycle_transition": f"{'+'.join(data['transitions'])} {target}"
                 if kind == "lifecycle_transition" else ""}[kind]
        return plan, label

    def load_components(self, entity: LoadComposableNodes, scope: Scope, enabled: bool)\
            -> tuple[str, list[dict[str, Any]]]:
        """The container's full name (as launch_ros resolves it) and each load request."""
        if not enabled:
            return describe(entity.target_container), []
        ctx = scope.context()
        container = entity.target_container
        if isinstance(container, Node):
            target = self.container_name(container, scope)
        else:
            text = perform(container, ctx)
            target = text if text.startswith("/") else "/" + text
        base = self.action_id(ActionKind.LOAD_COMPONENTS)
        return target, [component_plan(c, ctx, scope.namespace, scope.global_parameters,
                                       scope.remaps, f"{base}.{i + 1}", target)
                        for i, c in enumerate(entity.components)]

    def container_name(self, container: Node, scope: Scope) -> str:
        """A container given as the action: its name, once its plan exists."""
        proc_id = self.entity_ids.get(id(container))
        for proc in self.processes:
            if proc.id == proc_id and proc.full_name:
                return proc.full_name
        ctx = scope.context()
        name = perform(container.name, ctx) if container.name is not None else ""
        ns = join_namespace(scope.namespace, perform_optional(container.namespace, ctx))
        return join_namespace(ns, name)


def request_values(request: dict[str, Any], ctx: PerformContext, namespace: str,
                    origin: Origin | None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in request.items():
        if isinstance(value, dict):
            out[key] = request_values(value, ctx, namespace, origin)
            continue
        typed = typed_value(value, ctx, key, origin)
        out[key] = namespace if typed == "__ns" else typed
    return out


def describe_entity(entity: Any) -> str:
    text = entity.describe() if hasattr(entity, "describe") else repr(entity)
    origin = getattr(entity, "origin", None)
    return f"{text} ({origin})" if origin else text
