"""The scope a launch file's actions see: namespace, SetParameter/SetRemap, environment and
launch configurations, with their push/pop; and the name rules rcl applies to what they give."""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field, replace
from typing import Any

from ..describe.conditions import ConditionOutcome
from ..describe.entities import (
    AppendEnvironmentVariable,
    EnvironmentStack,
    Group,
    UnsetLaunchConfiguration,
)
from ..describe.substitutions import PerformContext, perform, text_to_bool
from ..errors import LaunchError
from .model import Trigger

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
