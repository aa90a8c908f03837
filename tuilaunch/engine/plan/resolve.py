"""Resolve a Description against argument values into a Plan.

Entities are visited in file order, as launch does, so an include that passes an argument
changes it for what follows (unless the include is scoped), and a declaration only sets a
default when the argument has no value yet.
"""

from __future__ import annotations

import atexit
import os
import re
import shlex
import shutil
import sys
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from ..describe.conditions import ConditionOutcome, condition_outcome
from ..describe.entities import (
    AppendEnvironmentVariable,
    CallService,
    DeclareLaunchArgument,
    DslOpaque,
    Entity,
    EnvironmentStack,
    ExecuteProcess,
    Group,
    IncludeLaunchDescription,
    IoCallbacks,
    LaunchDescription,
    LoadComposableNodes,
    LogInfo,
    Node,
    OpaqueFunction,
    PushRosNamespace,
    RegisterEventHandler,
    SetEnvironmentVariable,
    SetLaunchConfiguration,
    SetParameter,
    SetParameters,
    SetParametersFromFile,
    SetRemap,
    Shutdown,
    StopProcess,
    TimerAction,
    UnsetEnvironmentVariable,
    UnsetLaunchConfiguration,
    entity_list,
    pair_list,
)
from ..describe.events import When
from ..describe.lifecycle import ChangeStateAction, LifecycleTransition
from ..describe.loader import (
    LoadedFile,
    compat_modules,
    known_launch_files,
    load_file,
    set_command_line,
    unsupported_import,
)
from ..describe.parameter_files import Parameter, ParameterFile, substitute_text
from ..describe.substitutions import (
    PerformContext,
    describe,
    perform,
    perform_optional,
    text_to_bool,
)
from ..describe.values import ParamValue, flatten_parameters, typed_value
from ..errors import (
    ArgumentError,
    LaunchError,
    Origin,
    PackageError,
    origin_from_traceback,
    origin_outside_tuilaunch,
)
from ..packages import find_executable
from . import lifecycle as lifecycle_plan
from .components import component_plan, interfaces_warning
from .model import ActionPlan, ArgumentInfo, Plan, ProcessPlan, TreeItem, Trigger

DEFAULT_RESPAWN_MAX_RETRIES = -1  # as launch: respawn for as long as the launch runs

_FIND_EXEC = re.compile(r"\$\((?:find-exec|exec-in-pkg) ([^ )]+)[^)]*\)")
_UNSAFE_ID = re.compile(r"[^A-Za-z0-9_.+-]")
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


def _first(cmd: Any) -> Any:
    """The program of an ExecuteProcess cmd (to name a process that could not resolve)."""
    items = _items(cmd) if cmd is not None else []
    return items[0] if items else None


def _seconds(value: Any, ctx: PerformContext, what: str, origin: Origin | None) -> float:
    text = perform(value, ctx)
    try:
        return float(text)
    except ValueError:
        raise LaunchError(f"{what} {text!r} is not a number of seconds", origin) from None


def _rule_text(value: ParamValue) -> str:
    """A SetParameter value as launch_ros writes it after `-p name:=`: Python's str."""
    return str(value)


def _yaml_rule_text(value: ParamValue) -> str:
    """A launch_ros Parameter's value after `-p name:=`: YAML, so text stays text."""
    import yaml

    return str(yaml.safe_dump(value))


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


class Resolver:
    def __init__(self, arguments: Mapping[str, str], params_dir: Path,
                 entity_ids: dict[int, str] | None = None, counter: int = 0,
                 action_offset: int = 0) -> None:
        self.cli_arguments = dict(arguments)
        self.params_dir = params_dir
        self.processes: list[ProcessPlan] = []
        self.actions: list[ActionPlan] = []
        self.arguments: dict[str, ArgumentInfo] = {}
        self.entity_ids: dict[int, str] = {} if entity_ids is None else entity_ids
        self.lifecycle_entities: dict[str, Any] = {}  # process id -> LifecycleNode
        self.triggers: list[Trigger] = []
        self.warnings: list[str] = []
        self._include_stack: list[str] = []
        self._counter = counter
        self._action_offset = action_offset  # ids stay unique when actions join a running plan
        # --show-args: a required argument without a value, or a value outside the choices,
        # does not stop the walk (ros2 launch lists arguments without values)
        self.lenient = False
        self.first_error: LaunchError | None = None

    @property
    def id_counter(self) -> int:
        return self._counter

    def _action_id(self, kind: str) -> str:
        return f"{kind}-{self._action_offset + len(self.actions) + 1}"

    # --- entry -------------------------------------------------------------------------

    def resolve(self, loaded: LoadedFile) -> Plan:
        scope = Scope(dict(self.cli_arguments), loaded.path)
        root = TreeItem("group", os.path.basename(loaded.path), True)
        self._include_stack = [os.path.realpath(loaded.path)]
        self.walk(loaded.entities, scope, root)
        for trigger in self.triggers:
            if trigger.target_entity is not None:
                trigger.target = self.entity_ids.get(id(trigger.target_entity))
                if trigger.target is None:
                    self.warnings.append(
                        f"a trigger waits for {describe_entity(trigger.target_entity)}, which "
                        "this launch never runs: what it triggers will not start")
        self.warnings += lifecycle_plan.bind_targets(self.processes, self.actions,
                                                     self.lifecycle_entities, root)
        self.warnings += interfaces_warning(
            sum(len(p.components) for p in self.processes if p.enabled)
            + sum(len(a.data) for a in self.actions
                  if a.enabled and a.kind == "load_components"))
        declared = set(self.arguments)
        for name in self.cli_arguments:
            if name not in declared:
                self.warnings.append(
                    f"argument '{name}' is not declared by {os.path.basename(loaded.path)} "
                    f"or its includes (declared: {', '.join(sorted(declared)) or 'none'})")
        plan = Plan(loaded.path, list(self.arguments.values()), self.processes, self.actions,
                    root, self.params_dir, self.warnings)
        plan.entity_ids = self.entity_ids
        plan.id_counter = self._counter
        return plan

    def link_triggers(self) -> None:
        for trigger in self.triggers:
            if trigger.target_entity is not None and trigger.target is None:
                trigger.target = self.entity_ids.get(id(trigger.target_entity))

    def walk(self, entities: list[Any], scope: Scope, parent: TreeItem) -> None:
        for entity in entities:
            if self.lenient:
                self._visit_leniently(entity, scope, parent)
            elif scope.trigger is None or not scope.enabled:
                self.visit(entity, scope, parent)
            elif isinstance(entity, OpaqueFunction) or _custom_action(entity):
                self.defer([entity], scope, parent, "runs when the event happens")
            else:
                self._visit_or_defer(entity, scope, parent)

    def _visit_leniently(self, entity: Any, scope: Scope, parent: TreeItem) -> None:
        """--show-args: an entity that cannot be resolved without the values the user has
        not given (an include path, a package) is passed over, as ros2 launch passes over
        what it cannot read without a context; the first such error is kept."""
        try:
            self.visit(entity, scope, parent)
        except LaunchError as exc:
            if self.first_error is None:
                self.first_error = exc

    def _visit_or_defer(self, entity: Any, scope: Scope, parent: TreeItem) -> None:
        """Inside an event-gated branch, a value that cannot be performed yet (an unset
        variable, a file made later) only matters if the event happens: as in launch,
        the branch is then performed at event time, and fails only then."""
        marks = (len(self.processes), len(self.actions), len(parent.children),
                 len(self.triggers), dict(self.entity_ids), self._counter)
        try:
            self.visit(entity, scope, parent)
        except LaunchError as exc:
            del self.processes[marks[0]:], self.actions[marks[1]:]
            del parent.children[marks[2]:], self.triggers[marks[3]:]
            self.entity_ids.clear()
            self.entity_ids.update(marks[4])
            self._counter = marks[5]
            self.defer([entity], scope, parent, f"resolved when the event happens ({exc.message})")

    def defer(self, entities: list[Any], scope: Scope, parent: TreeItem, reason: str) -> None:
        enabled = scope.enabled
        what = ", ".join(describe_entity(e) for e in entities) or "nothing"
        action_id = self._action_id("deferred")
        plan = ActionPlan(action_id, "deferred", None, f"{what}: {reason}", scope.namespace, "",
                          enabled, scope.skipped_by, scope.trigger,
                          getattr(entities[0], "origin", None) if entities else None,
                          Deferred(entities, replace(scope, trigger=None), reason),
                          dict(scope.configurations))
        self.actions.append(plan)
        for entity in entities:
            self.entity_ids[id(entity)] = action_id
        parent.children.append(TreeItem("action", f"at event time: {what}", enabled,
                                        scope.namespace, scope.skipped_by, scope.trigger,
                                        action_id))

    def _next_id(self, base: str) -> str:
        """A process id is a file name too (its log, its parameters): never a path."""
        self._counter += 1
        safe = _UNSAFE_ID.sub("_", base).lstrip(".") or "process"
        return f"{safe}-{self._counter}"

    def _gate(self, entity: Any, scope: Scope) -> tuple[bool, ConditionOutcome | None]:
        """Whether an entity runs, and the condition that stops it if it does not."""
        enabled, skipped, _ = self._gate_outcome(entity, scope)
        return enabled, skipped

    def _gate_outcome(self, entity: Any, scope: Scope)\
            -> tuple[bool, ConditionOutcome | None, ConditionOutcome | None]:
        """Also the entity's own condition outcome; only read when its scope runs."""
        condition = getattr(entity, "condition", None)
        if not scope.enabled:
            return False, scope.skipped_by, None
        if condition is None:
            return True, None, None
        outcome = condition_outcome(condition, scope.context())
        return outcome.holds, (None if outcome.holds else outcome), outcome

    # --- dispatch ----------------------------------------------------------------------

    def visit(self, entity: Any, scope: Scope, parent: TreeItem) -> None:
        if isinstance(entity, LaunchDescription):
            self.walk(entity.entities, scope, parent)
        elif isinstance(entity, DeclareLaunchArgument):
            self.declare(entity, scope)
        elif isinstance(entity, Group):
            self.group(entity, scope, parent)
        elif isinstance(entity, Node | ExecuteProcess):
            self.process(entity, scope, parent)
        elif isinstance(entity, IncludeLaunchDescription):
            self.include(entity, scope, parent)
        elif isinstance(entity, PushRosNamespace):
            if self._gate(entity, scope)[0]:
                scope.namespace = join_namespace(scope.namespace,
                                                 perform(entity.namespace, scope.context()))
                scope.namespace_pushed = True
        elif isinstance(entity, LogInfo | CallService | SetParameters | Shutdown | IoCallbacks
                        | LoadComposableNodes | StopProcess | ChangeStateAction
                        | LifecycleTransition):
            self.action(entity, scope, parent)
        elif isinstance(entity, TimerAction):
            self.timer(entity, scope, parent)
        elif isinstance(entity, RegisterEventHandler):
            self.event_handler(entity, scope, parent)
        elif isinstance(entity, DslOpaque | OpaqueFunction) or _custom_action(entity):
            self.opaque(entity, scope, parent)
        elif isinstance(entity, SetEnvironmentVariable):
            if self._gate(entity, scope)[0]:
                ctx = scope.context()
                scope.env[perform(entity.name, ctx)] = perform(entity.value, ctx)
        elif isinstance(entity, UnsetEnvironmentVariable):
            if self._gate(entity, scope)[0]:
                scope.env[perform(entity.name, scope.context())] = None
        elif isinstance(entity, SetLaunchConfiguration):
            if self._gate(entity, scope)[0]:
                ctx = scope.context()
                scope.configurations[perform(entity.name, ctx)] = perform(entity.value, ctx)
        elif isinstance(entity, SetParameter):
            if self._gate(entity, scope)[0]:
                scope.global_parameters.append((entity.name, entity.value))
        elif isinstance(entity, SetParametersFromFile):
            if self._gate(entity, scope)[0]:
                scope.global_parameters.append((None, entity.filename))
        elif isinstance(entity, SetRemap):
            if self._gate(entity, scope)[0]:
                scope.remaps.append((entity.src, entity.dst))
        elif isinstance(entity, AppendEnvironmentVariable | EnvironmentStack
                        | UnsetLaunchConfiguration):
            if self._gate(entity, scope)[0]:
                apply_scope_action(entity, scope)
        else:
            where = getattr(entity, "origin", None)
            self.warnings.append(f"{where or scope.launch_file}: ignored {entity!r}, which "
                                 "tuilaunch does not know how to run")

    # --- arguments -----------------------------------------------------------------------

    def declare(self, decl: DeclareLaunchArgument, scope: Scope) -> None:
        ctx = scope.context()
        default = perform_optional(decl.default_value, ctx)
        if decl.name not in scope.configurations and default is not None:
            scope.configurations[decl.name] = default
        value = scope.configurations.get(decl.name)
        known = self.arguments.get(decl.name)
        if known is None:
            self.arguments[decl.name] = ArgumentInfo(
                decl.name, default, value, decl.description, decl.choices,
                decl.py_type or "str", scope.launch_file,
                decl.origin.line if decl.origin else None)
        elif scope.enabled and value is not None and value != known.value:
            # the argument form edits one value per name; a second declaration that holds
            # another value (the same file included again with other arguments) is shown
            where = os.path.basename(scope.launch_file)
            if decl.origin is not None:
                where += f":{decl.origin.line}"
            note = f"{value!r} in {where}"
            if note not in known.elsewhere:
                known.elsewhere.append(note)
        if not scope.enabled:
            return
        if self.lenient:
            if value is None:
                scope.configurations[decl.name] = ""
            return
        if value is None:
            raise ArgumentError(
                f"argument '{decl.name}' is required and has no value", decl.origin,
                hint=f"pass {decl.name}:=value" + (f" ({decl.description})"
                                                   if decl.description else ""))
        if decl.choices is not None and value not in decl.choices:
            raise ArgumentError(
                f"argument '{decl.name}' = {value!r} is not one of its choices: "
                f"{', '.join(decl.choices)}", decl.origin,
                hint=f"pass {decl.name}:=<one of {', '.join(decl.choices)}>")

    # --- groups and triggers ---------------------------------------------------------------

    def group(self, group: Group, outer: Scope, parent: TreeItem) -> None:
        enabled, skipped, outcome = self._gate_outcome(group, outer)
        scope = outer.child(group.scoped)
        scope.enabled, scope.skipped_by = enabled, skipped
        ctx = scope.context()
        if enabled:
            values = {perform(key, ctx): perform(value, ctx)
                      for key, value in group.launch_configurations.items()}
            if group.scoped and not group.forwarding:
                # launch's forwarding=False: the group sees only what it keeps; the pushed
                # namespace, SetParameter and SetRemap are launch configurations too
                scope.configurations.clear()
                scope.env.clear()
                scope.namespace, scope.namespace_pushed = "/", False
                scope.global_parameters, scope.remaps = [], []
            elif group.scoped:
                # launch_ros appends SetParameter / SetRemap values to the list the scope
                # already holds, so a scoped group adds to its parent's list when there is
                # one (ros2 launch behaves so): share it
                if outer.global_parameters:
                    scope.global_parameters = outer.global_parameters
                if outer.remaps:
                    scope.remaps = outer.remaps
            scope.configurations.update(values)
        if group.namespace is not None and enabled:
            scope.namespace = join_namespace(scope.namespace, perform(group.namespace, ctx))
            scope.namespace_pushed = True
        if group.when is not None:
            scope.trigger = self.when_trigger(group.when, scope)
        item = TreeItem("group", group_label(group, scope, outcome), enabled, scope.namespace,
                        outcome, scope.trigger if group.when is not None else None)
        if group.label in ("root", "opaque"):
            # the DSL's root group only carries the constructor namespace: no extra tree level
            item = parent
        else:
            parent.children.append(item)
        self.walk(group.children, scope, item)
        if not group.scoped and enabled:
            leak_back(scope, outer)

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
        self.triggers.append(trigger)
        return trigger

    def timer(self, timer: TimerAction, outer: Scope, parent: TreeItem) -> None:
        enabled, skipped = self._gate(timer, outer)
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
        scope.trigger = Trigger("timer", None, delay, None, outer.trigger)
        item = TreeItem("group", f"timer {delay:g} s", enabled, scope.namespace, None,
                        scope.trigger)
        parent.children.append(item)
        self.walk(timer.actions, scope, item)

    def event_handler(self, register: RegisterEventHandler, outer: Scope, parent: TreeItem)\
            -> None:
        handler = register.handler
        enabled, skipped = self._gate(register, outer)
        scope = outer.child(False)
        scope.enabled, scope.skipped_by = enabled, skipped
        io = handler.io
        if handler.on == "state":
            io = lifecycle_plan.state_trigger_io(handler, outer.context())  # type: ignore[arg-type]
        # a state handler without a target node applies to every lifecycle node: "*"
        target = "*" if handler.on == "state" and handler.target is None else None
        scope.trigger = Trigger(handler.on, target, 0.0, io, outer.trigger, handler.target,
                                repeat=handler.on == "state" and
                                not getattr(handler, "handle_once", False))
        self.triggers.append(scope.trigger)
        item = TreeItem("group", f"on {handler.on}", enabled, scope.namespace, None,
                        scope.trigger)
        parent.children.append(item)
        self.handler_body(handler.handler, handler.target is None and handler.on in
                          ("start", "exit", "io"), scope, item)

    def handler_body(self, body: Any, every_process: bool, scope: Scope, item: TreeItem)\
            -> None:
        if callable(body) and not isinstance(body, Entity):
            self.action(IoCallbacks([body]), scope, item)
        elif every_process:
            # performed again for each process's event, as launch does
            self.defer(entity_list(body), scope, item, "performed for every process's event")
        else:
            self.walk(entity_list(body), scope, item)

    def on_exit(self, entity: Node | ExecuteProcess, outer: Scope, parent: TreeItem) -> None:
        """`Node(on_exit=...)`: a handler for this process's exit."""
        scope = outer.child(False)
        scope.trigger = Trigger("exit", None, 0.0, None, outer.trigger, entity)
        self.triggers.append(scope.trigger)
        item = TreeItem("group", "on exit", scope.enabled, scope.namespace, None,
                        scope.trigger)
        parent.children.append(item)
        self.handler_body(entity.on_exit, False, scope, item)

    # --- includes and opaque functions -----------------------------------------------------

    def include(self, include: IncludeLaunchDescription, outer: Scope, parent: TreeItem)\
            -> None:
        enabled, skipped = self._gate(include, outer)
        ctx = outer.context()
        try:
            path = perform(include.location, ctx)
        except LaunchError:
            if enabled:
                raise
            parent.children.append(TreeItem("include", f"include {describe(include.location)}",
                                             False, outer.namespace, skipped))
            return
        if enabled:
            # arguments are performed before any is set, as launch does
            values = [(perform(k, ctx), perform(v, ctx)) for k, v in include.launch_arguments]
            for key, value in values:
                outer.configurations[key] = value
        scope = outer.child(False)
        scope.enabled, scope.skipped_by = enabled, skipped
        item = TreeItem("include", f"include {os.path.basename(path)}", enabled,
                        outer.namespace, skipped)
        parent.children.append(item)
        try:
            loaded = load_file(path, include.origin)
        except LaunchError:
            if enabled:
                raise
            return
        scope.launch_file = loaded.path
        real = os.path.realpath(loaded.path)
        if real in self._include_stack:
            if not enabled:
                return  # a skipped include is shown, not followed round its cycle
            cycle = [*self._include_stack[self._include_stack.index(real):], real]
            raise LaunchError("include cycle: " + " -> ".join(map(os.path.basename, cycle)),
                              include.origin, hint="an included file includes its includer")
        self._include_stack.append(real)
        try:
            self.walk(loaded.entities, scope, item)
        finally:
            self._include_stack.pop()
        if enabled:
            leak_back(scope, outer)  # an include is not a scope: what it pushes stays

    def opaque(self, entity: Any, scope: Scope, parent: TreeItem) -> None:
        """OpaqueFunctions, SimpleLauncher's opaque mode, and third-party actions' execute()."""
        if not self._gate(entity, scope)[0]:
            return
        context = scope.context()
        try:
            with compat_modules():
                if isinstance(entity, DslOpaque):
                    with entity.launcher.opaque_scope(context) as root:
                        result = entity.function()
                    produced = entity_list(result) if result is not None else [root]
                elif not isinstance(entity, OpaqueFunction):
                    produced = entity_list(entity.execute(context))
                else:
                    produced = entity_list(entity.function(context, *entity.args,
                                                           **entity.kwargs))
        except (LaunchError, BrokenPipeError):  # a closed stdout is the reader's choice
            raise
        except Exception as exc:  # user code: report its own file and line
            tb = sys.exc_info()[2]
            origin = origin_outside_tuilaunch(tb) or origin_from_traceback(
                tb, known_launch_files())
            missing = unsupported_import(exc) if isinstance(exc, ImportError | AttributeError) \
                else None
            what = "the opaque function" if isinstance(entity, OpaqueFunction | DslOpaque) \
                else f"{type(entity).__name__}.execute()"
            raise LaunchError(missing or f"{what} raised {type(exc).__name__}: {exc}",
                              origin or entity.origin) from None
        self.walk(produced, scope, parent)

    # --- processes -------------------------------------------------------------------------

    def process(self, entity: Node | ExecuteProcess, scope: Scope, parent: TreeItem) -> None:
        enabled, skipped = self._gate(entity, scope)
        counter = self._counter
        try:
            plan = self._process_plan(entity, scope, enabled, skipped)
        except LaunchError as exc:
            self._counter = counter  # the number the failed attempt took is this one's
            # what is not installed (a package, FindExecutable's program) fails the process
            # that needs it, and the rest runs; any other mistake in an enabled one stops
            if enabled and not isinstance(exc, PackageError):
                raise
            program = describe(getattr(entity, "executable", None)
                               or _first(getattr(entity, "cmd", None)) or "process")
            # `$(find-exec ros2)` names its process `ros2`
            base = os.path.basename(_FIND_EXEC.sub(r"\1", program)) or "process"
            given = getattr(entity, "name", None)
            name = given if isinstance(given, str) and given else None
            plan = ProcessPlan(self._next_id(name or base), entity.kind, name, scope.namespace,
                               None,
                               base, [], {}, [], [], [], {}, False, None, False, 0.0, 0, None,
                               None, enabled, skipped, scope.trigger, entity.origin,
                               error=exc.message if enabled else f"not resolved: {exc.message}")
        plan.source = entity
        self.processes.append(plan)
        self.entity_ids[id(entity)] = plan.id
        if getattr(entity, "lifecycle", False):
            self.lifecycle_entities[plan.id] = entity
        parent.children.append(TreeItem("process", plan.label, enabled, plan.namespace,
                                        skipped, scope.trigger, plan.id))
        if entity.on_exit is not None:
            self.on_exit(entity, scope, parent)

    def _process_plan(self, entity: Node | ExecuteProcess, scope: Scope, enabled: bool,
                      skipped: ConditionOutcome | None) -> ProcessPlan:
        ctx = scope.context()
        env = {k: v for k, v in scope.env.items() if v is not None}
        if entity.additional_env:
            env.update({perform(k, ctx): perform(v, ctx) for k, v in entity.additional_env.items()})
        clear_env = entity.env is not None
        if entity.env is not None:
            env = {perform(k, ctx): perform(v, ctx) for k, v in entity.env.items()}
        prefix = shlex.split(perform(entity.prefix, ctx)) if entity.prefix is not None else []
        respawn = text_to_bool(perform(entity.respawn, ctx)) or False
        respawn_delay = _seconds(entity.respawn_delay, ctx, "respawn_delay", entity.origin) \
            if entity.respawn_delay is not None else 0.0
        retries = entity.respawn_max_retries
        common = dict(
            env=env, clear_env=clear_env, cwd=perform_optional(entity.cwd, ctx),
            respawn=respawn, respawn_delay=respawn_delay,
            respawn_max_retries=DEFAULT_RESPAWN_MAX_RETRIES if retries is None else retries,
            sigterm_timeout=_float_or_none(entity.sigterm_timeout, ctx, "sigterm_timeout",
                                           entity.origin),
            sigkill_timeout=_float_or_none(entity.sigkill_timeout, ctx, "sigkill_timeout",
                                           entity.origin),
            output=str(perform(entity.output, ctx)) if entity.output is not None else "screen",
            emulate_tty=None if getattr(entity, "emulate_tty", None) is None
            else bool(text_to_bool(perform(entity.emulate_tty, ctx))),
            enabled=enabled, skipped_by=skipped, trigger=scope.trigger, origin=entity.origin,
        )
        if isinstance(entity, ExecuteProcess):
            return self._execute_process_plan(entity, ctx, scope, prefix, common)
        return self._node_plan(entity, ctx, scope, prefix, common)

    def _execute_process_plan(self, entity: ExecuteProcess, ctx: PerformContext, scope: Scope,
                              prefix: list[str], common: dict[str, Any]) -> ProcessPlan:
        cmd = [perform(part, ctx) for part in _items(entity.cmd)]
        cmd = [c for c in cmd if c != ""]
        if entity.shell:
            cmd = ["/bin/sh", "-c", " ".join(cmd)]
        if not cmd:
            raise LaunchError("ExecuteProcess with an empty cmd", entity.origin)
        name = perform_optional(entity.name, ctx)
        base = name or os.path.basename(cmd[0].split()[0])
        error = None
        if not entity.shell and "/" not in cmd[0] and shutil.which(cmd[0]) is None:
            error = f"command '{cmd[0]}' not found on PATH"
        return ProcessPlan(self._next_id(base), "process", name, scope.namespace, None, cmd[0],
                           prefix + cmd, {}, [], [], [], error=error, **common)

    def _node_plan(self, entity: Node, ctx: PerformContext, scope: Scope, prefix: list[str],
                   common: dict[str, Any]) -> ProcessPlan:
        package = perform_optional(entity.package, ctx)
        executable = perform(entity.executable, ctx)
        name = perform_optional(entity.name, ctx) or None
        own_namespace = perform_optional(entity.namespace, ctx)
        namespace = join_namespace(scope.namespace, own_namespace)
        # the node's name when it has one: `[monitor-5]` says more than `[listener-5]`
        proc_id = self._next_id(name or os.path.basename(executable))
        error = (name_problem(name) if name else None) or namespace_problem(namespace)
        exe_path = executable
        if package is not None:
            try:
                exe_path = str(find_executable(package, executable, entity.origin))
            except PackageError as exc:
                error = error or exc.message
        elif shutil.which(executable) is None:
            error = error or f"executable '{executable}' not found on PATH"
        merged: dict[str, ParamValue] = {}
        user_files: list[str] = []
        generated: list[tuple[str, dict[str, Any]]] = []
        params_args: list[str] = []
        # launch_ros: SetParameter pairs as `-p name:=value` and SetParametersFromFile files
        # first, in order; then each of the node's own dicts in a file of its own, each
        # Parameter as `-p`, each file as it is
        items: list[Any] = [("global", value if key is None else {key: value})
                            for key, value in scope.global_parameters]
        items += [("own", item) for item in _items(entity.parameters)]
        for origin_kind, item in items:
            if isinstance(item, Parameter):
                values = flatten_parameters(item.as_dict(), ctx, entity.origin)
                merged.update(values)
                params_args += [a for name, value in values.items()
                                for a in ("-p", f"{name}:={_yaml_rule_text(value)}")]
                continue
            if isinstance(item, dict):
                values = flatten_parameters(item, ctx, entity.origin)
                merged.update(values)
                if origin_kind == "global":
                    params_args += [a for name, value in values.items()
                                    for a in ("-p", f"{name}:={_rule_text(value)}")]
                else:
                    generated.append(self._params_file(proc_id, len(generated), values,
                                                       params_args))
                continue
            if isinstance(item, ParameterFile):
                path = self._parameter_file(item, ctx, proc_id, len(user_files))
            else:
                path = perform(item, ctx)
            if not os.path.isfile(path):
                # launch_ros warns and starts the node without it
                if common["enabled"]:
                    where = f" ({entity.origin})" if entity.origin else ""
                    self.warnings.append(f"parameter file {path} is not a file: "
                                         f"{name or executable} starts without it{where}")
                continue
            user_files.append(path)
            params_args += ["--params-file", path]
        own_remaps = pair_list(entity.remappings, "remappings", entity.origin)
        remappings = [[perform(a, ctx), perform(b, ctx)] for a, b in [*scope.remaps, *own_remaps]]
        arguments = [perform(a, ctx) for a in _items(entity.arguments)]
        ros_arguments = [perform(a, ctx) for a in _items(entity.ros_arguments)]
        # launch_ros: the user's ros_arguments in a block of their own, then always a
        # `--ros-args` block for the name, namespace, parameters and remappings
        cmd = [*prefix, exe_path, *arguments]
        if entity.ros_arguments is not None:
            cmd += ["--ros-args", *ros_arguments]
        cmd.append("--ros-args")
        if name:
            cmd += ["-r", f"__node:={name}"]
        if own_namespace is not None or scope.namespace_pushed:
            cmd += ["-r", f"__ns:={namespace}"]
        cmd += params_args
        for src, dst in remappings:
            cmd += ["-r", f"{src}:={dst}"]
        if getattr(entity, "shell", False):
            cmd = ["/bin/sh", "-c", " ".join(cmd)]
        # launch_ros loads components under the pushed namespace, not the container's own
        container = join_namespace(namespace, name) if name else None
        components = [component_plan(c, ctx, scope.namespace, scope.global_parameters,
                                     scope.remaps, f"{proc_id}.{i + 1}", container)
                      for i, c in enumerate(entity.components)]
        autostart = text_to_bool(perform(getattr(entity, "autostart", False), ctx)) or False
        return ProcessPlan(proc_id, entity.kind, name, namespace, package, executable, cmd,
                           merged, user_files, generated, remappings, error=error,
                           components=components, lifecycle=getattr(entity, "lifecycle", False),
                           autostart=autostart, **common)

    def _parameter_file(self, item: ParameterFile, ctx: PerformContext, proc_id: str,
                        index: int) -> str:
        path = item.path(ctx)
        if not item.substitutes(ctx):
            return path
        try:
            with open(path, encoding="utf-8") as handle:
                text = handle.read()
        except OSError as exc:
            raise LaunchError(f"parameter file {path} cannot be read: {exc.strerror or exc}",
                              item.origin) from None
        out = self.params_dir / f"{proc_id}-file{index + 1}.yaml"
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(substitute_text(text, ctx, item.origin), encoding="utf-8")
        return str(out)

    def _params_file(self, proc_id: str, index: int, params: dict[str, Any],
                     params_args: list[str]) -> tuple[str, dict[str, Any]]:
        suffix = "" if index == 0 else f"-{index + 1}"
        path = str(self.params_dir / f"{proc_id}{suffix}.yaml")
        params_args += ["--params-file", path]
        return path, dict(params)

    # --- actions ---------------------------------------------------------------------------

    def action(self, entity: Any, scope: Scope, parent: TreeItem) -> None:
        enabled, skipped = self._gate(entity, scope)
        ctx = scope.context()
        target: str | None = None
        data: Any = None
        verbosity = ""
        if isinstance(entity, LogInfo):
            kind = "log"
            data = perform(entity.msg, ctx) if enabled else describe(entity.msg)
        elif isinstance(entity, CallService):
            kind = "call_service"
            if enabled:
                target = resolve_name(scope.namespace, perform(entity.server, ctx))
                data = _request_values(entity.request, ctx, scope.namespace, entity.origin)
                verbosity = perform(entity.verbosity, ctx)
            else:
                target = describe(entity.server)
        elif isinstance(entity, SetParameters):
            kind = "set_parameters"
            if enabled:
                target = resolve_name(scope.namespace, perform(entity.node_name, ctx))
                data = flatten_parameters(entity.parameters, ctx, entity.origin)
                verbosity = perform(entity.verbosity, ctx)
            else:
                target = describe(entity.node_name)
        elif isinstance(entity, Shutdown):
            kind = "shutdown"
            data = perform(entity.reason, ctx) if enabled else describe(entity.reason)
        elif isinstance(entity, StopProcess):
            kind = "stop_process"
            target = self.entity_ids.get(id(entity.target)) or describe_entity(entity.target)
        elif isinstance(entity, LoadComposableNodes):
            kind = "load_components"
            target, data = self._load_components(entity, scope, enabled)
        elif isinstance(entity, ChangeStateAction | LifecycleTransition):
            kind = "lifecycle_transition"
            target, data = lifecycle_plan.transition_action(entity, ctx) if enabled else (
                describe(getattr(entity, "node_names", "lifecycle nodes")),
                {"transitions": [], "transition_ids": [], "node_names": [], "targets": []})
        else:
            kind = "event_callback"
            data = len(entity.callbacks)
        action_id = self._action_id(kind)
        plan = ActionPlan(action_id, kind, target, data, scope.namespace, verbosity, enabled,
                          skipped, scope.trigger, entity.origin, entity,
                          dict(scope.configurations))
        self.actions.append(plan)
        self.entity_ids[id(entity)] = action_id
        label = {"log": f"log: {data}", "call_service": f"call {target}",
                 "set_parameters": f"set parameters of {target}",
                 "shutdown": "shutdown", "event_callback": "event callback",
                 "stop_process": f"stop {target}",
                 "load_components": f"load components into {target}",
                 "lifecycle_transition": f"{'+'.join(data['transitions'])} {target}"
                 if kind == "lifecycle_transition" else ""}[kind]
        parent.children.append(TreeItem("action", label, enabled, scope.namespace, skipped,
                                        scope.trigger, action_id))


    def _load_components(self, entity: LoadComposableNodes, scope: Scope, enabled: bool)\
            -> tuple[str, list[dict[str, Any]]]:
        """The container's full name (as launch_ros resolves it) and each load request."""
        if not enabled:
            return describe(entity.target_container), []
        ctx = scope.context()
        container = entity.target_container
        if isinstance(container, Node):
            target = self._container_name(container, scope)
        else:
            text = perform(container, ctx)
            target = text if text.startswith("/") else "/" + text
        base = self._action_id("load_components")
        return target, [component_plan(c, ctx, scope.namespace, scope.global_parameters,
                                       scope.remaps, f"{base}.{i + 1}", target)
                        for i, c in enumerate(entity.components)]

    def _container_name(self, container: Node, scope: Scope) -> str:
        """A container given as the action: its name, once its plan exists."""
        proc_id = self.entity_ids.get(id(container))
        for proc in self.processes:
            if proc.id == proc_id and proc.full_name:
                return proc.full_name
        ctx = scope.context()
        name = perform(container.name, ctx) if container.name is not None else ""
        ns = join_namespace(scope.namespace, perform_optional(container.namespace, ctx))
        return join_namespace(ns, name)


def _custom_action(entity: Any) -> bool:
    """A launch.Action subclass written outside tuilaunch: it runs through execute()."""
    return isinstance(entity, Entity) and callable(getattr(entity, "execute", None))


def apply_scope_action(entity: Any, scope: Scope) -> None:
    """Environment and launch-configuration edits that change what follows in a scope."""
    ctx = scope.context()
    if isinstance(entity, AppendEnvironmentVariable):
        name, value = perform(entity.name, ctx), perform(entity.value, ctx)
        old = scope.env[name] if name in scope.env else os.environ.get(name)
        separator = perform(entity.separator, ctx)
        prepend = entity.prepend if isinstance(entity.prepend, bool) else \
            text_to_bool(perform(entity.prepend, ctx)) or False
        if old:
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


def _request_values(request: dict[str, Any], ctx: PerformContext, namespace: str,
                    origin: Origin | None) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in request.items():
        if isinstance(value, dict):
            out[key] = _request_values(value, ctx, namespace, origin)
            continue
        typed = typed_value(value, ctx, key, origin)
        out[key] = namespace if typed == "__ns" else typed
    return out


def _items(value: Any) -> list[Any]:
    if value is None:
        return []
    if isinstance(value, list | tuple):
        return list(value)
    return [value]


def _float_or_none(value: Any, ctx: PerformContext, what: str, origin: Origin | None)\
        -> float | None:
    return None if value is None else _seconds(value, ctx, what, origin)


def describe_entity(entity: Any) -> str:
    text = entity.describe() if hasattr(entity, "describe") else repr(entity)
    origin = getattr(entity, "origin", None)
    return f"{text} ({origin})" if origin else text


def group_label(group: Group, scope: Scope, outcome: ConditionOutcome | None) -> str:
    parts = []
    if group.namespace is not None:
        parts.append(f"ns {scope.namespace}")
    if group.condition is not None:
        parts.append(group.condition.describe())
    return ", ".join(parts) or group.label or "group"


_params_dir: Path | None = None


def default_params_dir() -> Path:
    """One private folder per tuilaunch process (mkdtemp: 0700, a name nobody can guess)."""
    global _params_dir
    # made anew when a finished run removed it (a launcher may plan several runs)
    if _params_dir is None or not _params_dir.is_dir():
        _params_dir = Path(tempfile.mkdtemp(prefix=f"tuilaunch-{os.getpid()}-params-"))
        atexit.register(shutil.rmtree, _params_dir, True)
    return _params_dir


def declared_arguments(loaded: LoadedFile, arguments: Mapping[str, str] | None = None)\
        -> tuple[list[ArgumentInfo], LaunchError | None]:
    """Every argument the file and its includes declare, for `--show-args`, found without
    values for the required ones; the first error that hid some of them, if one did."""
    resolver = Resolver(arguments or {}, default_params_dir())
    resolver.lenient = True
    set_command_line(arguments=dict(arguments or {}))
    try:
        resolver.resolve(loaded)
    except LaunchError as exc:
        return list(resolver.arguments.values()), exc
    return list(resolver.arguments.values()), resolver.first_error


def resolve(loaded: LoadedFile, arguments: Mapping[str, str] | None = None,
            params_dir: Path | None = None) -> Plan:
    """The Plan for these argument values (`name -> text`, as given on the command line)."""
    resolver = Resolver(arguments or {}, params_dir or default_params_dir())
    set_command_line(arguments=dict(arguments or {}))
    return resolver.resolve(loaded)


__all__ = ["Resolver", "declared_arguments", "join_namespace", "resolve"]
