"""The scope a launch file's actions see: namespace, SetParameter/SetRemap, environment and
launch configurations, with their push/pop; and the name rules rcl applies to what they give."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

from ..describe.conditions import ConditionOutcome
from ..describe.entities import (
    AppendEnvironmentVariable,
    Entity,
    EnvironmentStack,
    ExecuteProcess,
    Group,
    IoCallbacks,
    Node,
    RegisterEventHandler,
    TimerAction,
    TriggerOn,
    UnsetLaunchConfiguration,
    entity_list,
)
from ..describe.events import When
from ..describe.substitutions import PerformContext, perform, text_to_bool
from ..errors import ArgumentError, LaunchError
from . import lifecycle as lifecycle_plan
from .model import TreeItem, Trigger

_NAME_CHAR = re.compile(r"[^A-Za-z0-9_]")
_NAME_RULE = "letters, digits and _, not starting with a digit"


def name_problem(name: str, what: str = "node name") -> str | None:
    """Why rcl would refuse this node name, naming the bad character; None when valid."""
    if not name:
        return f"{what} is empty"
    bad = _NAME_CHAR.search(name)
    if bad:
        return (f"{what} {name!r} has {bad.group()!r} at position {bad.start() + 1} "
                f"({_NAME_RULE})")
    if name[0].isdigit():
        return f"{what} {name!r} starts with the digit {name[0]!r} ({_NAME_RULE})"
    return None


def namespace_problem(namespace: str) -> str | None:
    """Why rcl would refuse this (absolute) namespace, naming the bad character."""
    bad = re.search(r"[^A-Za-z0-9_/]", namespace)
    if bad:
        return (f"namespace {namespace!r} has {bad.group()!r} at position {bad.start() + 1} "
                f"(each part: {_NAME_RULE})")
    digit = re.search(r"/[0-9]", namespace)
    if digit:
        return (f"namespace {namespace!r} has a part starting with the digit "
                f"{digit.group()[1]!r} at position {digit.start() + 2} (each part: {_NAME_RULE})")
    return None


def join_namespace(base: str, ns: str | None) -> str:
    """Relative namespaces append, absolute ones reset; the result is absolute."""
    if not ns:
        return base
    joined = ns if ns.startswith("/") else base.rstrip("/") + "/" + ns
    parts = [p for p in joined.split("/") if p]
    return "/" + "/".join(parts)


def resolve_name(namespace: str, name: str) -> str:
    return join_namespace(namespace, name) if not name.startswith("/") else \
        join_namespace("/", name)


@dataclass
class Scope:
    configurations: dict[str, str]
    launch_file: str
    namespace: str = "/"
    # launch_ros passes `-r __ns:=` once a namespace was pushed, even "/"
    namespace_pushed: bool = False
    enabled: bool = True
    skipped_by: ConditionOutcome | None = None
    trigger: Trigger | None = None
    global_parameters: list[tuple[Any, Any]] = field(default_factory=list)
    remaps: list[tuple[Any, Any]] = field(default_factory=list)
    env: dict[str, str | None] = field(default_factory=dict)
    event_locals: dict[str, Any] = field(default_factory=dict)
    stacks: dict[str, list[Any]] = field(default_factory=dict)

    def child(self, scoped: bool) -> Scope:
        return replace(
            self,
            configurations=dict(self.configurations) if scoped else self.configurations,
            global_parameters=list(self.global_parameters),
            remaps=list(self.remaps),
            env=dict(self.env),
            stacks={k: list(v) for k, v in self.stacks.items()},
        )

    def context(self) -> PerformContext:
        return PerformContext(self.configurations, self.launch_file,
                              global_parameters=self.global_parameters,
                              event_locals=dict(self.event_locals))


def leak_back(inner: Scope, outer: Scope) -> None:
    """What an unscoped group or an included file pushed stays pushed after it, as in launch:
    the namespace, SetParameter, SetRemap and the environment (launch configurations are
    already the same dict)."""
    outer.namespace, outer.namespace_pushed = inner.namespace, inner.namespace_pushed
    outer.global_parameters, outer.remaps = inner.global_parameters, inner.remaps
    outer.env = inner.env


@dataclass
class Deferred:
    """Entities performed when an event happens, with the scope they were written in.

    What a file puts in an event handler, a timer or OnShutdown and cannot be described
    ahead (an OpaqueFunction, a substitution that fails until then, the body of a handler
    that applies to every process) is kept like this and performed by the supervisor."""

    entities: list[Any]
    scope: Scope
    reason: str


def apply_scope_action(entity: Any, scope: Scope) -> None:
    """Environment and launch-configuration edits that change what follows in a scope."""
    ctx = scope.context()
    if isinstance(entity, AppendEnvironmentVariable):
        name, value = perform(entity.name, ctx), perform(entity.value, ctx)
        old = scope.env[name] if name in scope.env else os.environ.get(name)
        separator = perform(entity.separator, ctx)
        prepend = entity.prepend if isinstance(entity.prepend, bool) else \
            text_to_bool(perform(entity.prepend, ctx)) or False
        if old is not None:  # launch: set, even empty, gets the separator
            value = value + separator + old if prepend else old + separator + value
        scope.env[name] = value
    elif isinstance(entity, UnsetLaunchConfiguration):
        scope.configurations.pop(perform(entity.name, ctx), None)
    elif isinstance(entity, EnvironmentStack):
        target: dict[str, Any] = scope.env if entity.what == "env" else scope.configurations
        stack = scope.stacks.setdefault(entity.what, [])
        if entity.op == "push":
            stack.append(dict(target))
        elif entity.op == "pop":
            if not stack:
                raise LaunchError(f"Pop{'Environment' if entity.what == 'env' else ''}"
                                  "... without a matching Push", entity.origin)
            saved = stack.pop()
            target.clear()
            target.update(saved)
        else:
            values = {perform(k, ctx): perform(v, ctx) for k, v in (entity.values or {}).items()}
            target.clear()
            target.update(values)


def group_label(group: Group, scope: Scope, outcome: ConditionOutcome | None) -> str:
    parts = []
    if group.namespace is not None:
        parts.append(f"ns {scope.namespace}")
    if group.condition is not None:
        parts.append(group.condition.describe())
    return ", ".join(parts) or group.label or "group"


class WalkHost(Protocol):
    """What the scopes of events need of the resolver walking the file."""

    triggers: list[Trigger]

    def gate(self, entity: Any, scope: Scope) -> tuple[bool, ConditionOutcome | None]: ...

    def walk(self, entities: list[Any], scope: Scope, parent: TreeItem) -> None: ...

    def defer(self, entities: list[Any], scope: Scope, parent: TreeItem, reason: str) -> None:
        ...

    def action(self, entity: Any, scope: Scope, parent: TreeItem) -> None: ...


class EventScopes:
    """The scopes that wait for something: a `When` group, a TimerAction, a registered event
    handler, a process's `on_exit`. Each opens a scope whose Trigger says what it waits for
    (kept in the host's `triggers`, linked to their targets once the file is walked), and a
    row of the tree; the host walks what it holds."""

    def __init__(self, host: WalkHost) -> None:
        self.host = host

    def when_trigger(self, when: When, scope: Scope) -> Trigger:
        delay = 0.0
        if when.delay is not None and scope.enabled:
            text = perform(when.delay, scope.context())
            try:
                delay = float(text)
            except ValueError:
                raise ArgumentError(f"When(delay=...) gave {text!r}, which is not a number",
                                    when.origin, hint="a delay is in seconds") from None
        trigger = Trigger(when.on, None, delay, when.io, scope.trigger, when.target)
        self.host.triggers.append(trigger)
        return trigger

    def timer(self, timer: TimerAction, outer: Scope, parent: TreeItem) -> None:
        enabled, skipped = self.host.gate(timer, outer)
        scope = outer.child(False)
        scope.enabled, scope.skipped_by = enabled, skipped
        delay = 0.0
        if enabled:
            text = perform(timer.period, scope.context())
            try:
                delay = float(text)
            except ValueError:
                raise ArgumentError(f"TimerAction period {text!r} is not a number",
                                    timer.origin) from None
        scope.trigger = Trigger(TriggerOn.TIMER, None, delay, None, outer.trigger)
        item = TreeItem("group", f"timer {delay:g} s", enabled, scope.namespace, None,
                        scope.trigger)
        parent.children.append(item)
        self.host.walk(timer.actions, scope, item)

    def event_handler(self, register: RegisterEventHandler, outer: Scope, parent: TreeItem)\
            -> None:
        handler = register.handler
        enabled, skipped = self.host.gate(register, outer)
        scope = outer.child(False)
        scope.enabled, scope.skipped_by = enabled, skipped
        io = handler.io
        if handler.on == TriggerOn.STATE:
            io = lifecycle_plan.state_trigger_io(handler, outer.context())  # type: ignore[arg-type]
        # a state handler without a target node applies to every lifecycle node: "*"
        target = "*" if handler.on == TriggerOn.STATE and handler.target is None else None
        scope.trigger = Trigger(handler.on, target, 0.0, io, outer.trigger, handler.target,
                                repeat=handler.on == TriggerOn.STATE and
                                not getattr(handler, "handle_once", False))
        self.host.triggers.append(scope.trigger)
        item = TreeItem("group", f"on {handler.on}", enabled, scope.namespace, None,
                        scope.trigger)
        parent.children.append(item)
        self.handler_body(handler.handler, handler.target is None and handler.on in
                          (TriggerOn.START, TriggerOn.EXIT, TriggerOn.IO), scope, item)

    def handler_body(self, body: Any, every_process: bool, scope: Scope, item: TreeItem)\
            -> None:
        if callable(body) and not isinstance(body, Entity):
            self.host.action(IoCallbacks([body]), scope, item)
        elif every_process:
            # performed again for each process's event, as launch does
            self.host.defer(entity_list(body), scope, item, "performed for every process's event")
        else:
            self.host.walk(entity_list(body), scope, item)

    def on_exit(self, entity: Node | ExecuteProcess, outer: Scope, parent: TreeItem) -> None:
        """`Node(on_exit=...)`: a handler for this process's exit."""
        scope = outer.child(False)
        scope.trigger = Trigger(TriggerOn.EXIT, None, 0.0, None, outer.trigger, entity)
        self.host.triggers.append(scope.trigger)
        item = TreeItem("group", "on exit", scope.enabled, scope.namespace, None,
                        scope.trigger)
        parent.children.append(item)
        self.handler_body(entity.on_exit, False, scope, item)
