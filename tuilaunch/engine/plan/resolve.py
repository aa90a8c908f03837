"""Resolve a Description against argument values into a Plan.

Entities are visited in file order, as launch does, so an include that passes an argument
changes it for what follows (unless the include is scoped), and a declaration only sets a
default when the argument has no value yet.

This module walks the entities (dispatch, groups, triggers, event handlers, includes); what
each kind becomes is built next door: scope.py (namespace, SetParameter/SetRemap,
environment push/pop), command/command_line.py (a process's or node's command line), actions.py
(log, call_service, set_parameters, ...), arguments.py, opaque.py.

A little over 500 lines on purpose: `Resolver` is one recursive visitor (visit -> group /
include / event handler -> walk -> visit); its visits call each other and stay together.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..describe import entities as en
from ..describe.conditions import ConditionOutcome, condition_outcome
from ..describe.environ import EnvironView
from ..describe.lifecycle import ChangeStateAction, LifecycleTransition
from ..describe.python.loader import (
    LoadedFile,
    load_file,
    set_command_line,
)
from ..describe.substitutions import (
    describe,
    perform,
)
from ..errors import (
    LaunchError,
    PackageError,
)
from . import lifecycle as lifecycle_plan
from .actions import ActionPlanner, describe_entity
from .arguments import declare_argument, type_notes
from .command.command_line import LAUNCH_CONFIGURATIONS, ProcessPlanner
from .command.prefix import LAUNCH_PREFIX, LAUNCH_PREFIX_FILTER
from .components import interfaces_warning
from .model import ActionKind, ActionPlan, ArgumentInfo, Plan, ProcessPlan, TreeItem, Trigger
from .opaque import is_custom_action, perform_opaque
from .params import default_params_dir, remove_default_params_dir
from .scope import (
    Deferred,
    EventScopes,
    Scope,
    apply_scope_action,
    group_label,
    join_namespace,
    leak_back,
)

_UNSAFE_ID = re.compile(r"[^A-Za-z0-9_.+-]")
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
        self.events = EventScopes(self)  # what waits for an event, a timer, an exit
        self.warnings: list[str] = []
        self._include_stack: list[str] = []
        self._counter = counter
        self._action_offset = action_offset  # ids stay unique when actions join a running plan
        # --show-args: a required argument without a value, or a value outside the choices,
        # does not stop the walk (ros2 launch lists arguments without values)
        self.lenient = False
        self.first_error: LaunchError | None = None
        self._environ: EnvironView | None = None
        self.process_planner = ProcessPlanner(self._next_id, params_dir, self.warnings)
        self.action_planner = ActionPlanner(self._action_id, self.entity_ids, self.processes)

    @property
    def id_counter(self) -> int:
        return self._counter

    def _action_id(self, kind: str) -> str:
        return f"{kind}-{self._action_offset + len(self.actions) + 1}"

    # --- entry -------------------------------------------------------------------------

    def resolve(self, loaded: LoadedFile) -> Plan:
        scope = Scope(dict(self.cli_arguments), loaded.path, env=dict(loaded.environ))
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
                  if a.enabled and a.kind == ActionKind.LOAD_COMPONENTS))
        declared = set(self.arguments)
        for name in self.cli_arguments:
            if name not in declared and name not in LAUNCH_OWN:
                self.warnings.append(undeclared_warning(name, declared, loaded.path))
        # a value unlike its default's type (gain:=abc for 1.0): passed as written, as ros2
        # launch does, and said wherever the plan's warnings are (start, --print, the TUI)
        self.warnings += [f"{note} (passed as written)" for note in type_notes(
            list(self.arguments.values()), self.cli_arguments)]
        plan = Plan(loaded.path, list(self.arguments.values()), self.processes, self.actions,
                    root, self.params_dir, self.warnings)
        plan.entity_ids = self.entity_ids
        plan.id_counter = self._counter
        plan.environ = dict(scope.env)
        return plan

    def link_triggers(self) -> None:
        for trigger in self.triggers:
            if trigger.target_entity is not None and trigger.target is None:
                trigger.target = self.entity_ids.get(id(trigger.target_entity))

    def walk(self, entities: list[Any], scope: Scope, parent: TreeItem) -> None:
        if self._environ is None:
            # the outermost walk: while it lasts, os.environ shows the environment of the
            # scope being visited, as launch's does; the launcher's own comes back after
            self._environ = EnvironView()
            try:
                self.walk(entities, scope, parent)
            finally:
                self._environ.restore()
                self._environ = None
            return
        for entity in entities:
            if self.lenient:
                self._visit_leniently(entity, scope, parent)
            elif scope.trigger is None or not scope.enabled:
                self.visit(entity, scope, parent)
            elif isinstance(entity, en.OpaqueFunction) or is_custom_action(entity):
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
        action_id = self._action_id(ActionKind.DEFERRED)
        plan = ActionPlan(action_id, ActionKind.DEFERRED, None, f"{what}: {reason}",
                          scope.namespace, "",
                          enabled, scope.skipped_by, scope.trigger,
                          getattr(entities[0], "origin", None) if entities else None,
                          Deferred(entities, replace(scope, trigger=None), reason),
                          dict(scope.configurations), dict(scope.env), scope.launch_file)
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

    def gate(self, entity: Any, scope: Scope) -> tuple[bool, ConditionOutcome | None]:
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
        if self._environ is not None:
            self._environ.show(scope.env)
        if isinstance(entity, en.LaunchDescription):
            self.walk(entity.entities, scope, parent)
        elif isinstance(entity, en.DeclareLaunchArgument):
            declare_argument(self.arguments, self.lenient, entity, scope)
        elif isinstance(entity, en.Group):
            self.group(entity, scope, parent)
        elif isinstance(entity, en.Node | en.ExecuteProcess):
            self.process(entity, scope, parent)
        elif isinstance(entity, en.IncludeLaunchDescription):
            self.include(entity, scope, parent)
        elif isinstance(entity, en.PushRosNamespace):
            if self.gate(entity, scope)[0]:
                scope.namespace = join_namespace(scope.namespace,
                                                 perform(entity.namespace, scope.context()))
                scope.namespace_pushed = True
        elif isinstance(entity, en.LogInfo | en.CallService | en.SetParameters | en.Shutdown
                        | en.IoCallbacks | en.LoadComposableNodes | en.StopProcess
                        | en.SendSignal | en.OpaqueCoroutine | ChangeStateAction
                        | LifecycleTransition):
            self.action(entity, scope, parent)
        elif isinstance(entity, en.TimerAction):
            self.events.timer(entity, scope, parent)
        elif isinstance(entity, en.RegisterEventHandler):
            self.events.event_handler(entity, scope, parent)
        elif isinstance(entity, en.DslOpaque | en.OpaqueFunction) or is_custom_action(entity):
            self.opaque(entity, scope, parent)
        elif isinstance(entity, en.SetEnvironmentVariable | en.SetLaunchConfiguration):
            if self.gate(entity, scope)[0]:
                ctx = scope.context()
                into: dict[str, Any] = scope.env if isinstance(entity, en.SetEnvironmentVariable) \
                    else scope.configurations
                into[perform(entity.name, ctx)] = perform(entity.value, ctx)
        elif isinstance(entity, en.UnsetEnvironmentVariable):
            if self.gate(entity, scope)[0]:
                scope.env[perform(entity.name, scope.context())] = None
        elif isinstance(entity, en.SetParameter):
            if self.gate(entity, scope)[0]:
                scope.global_parameters.append((entity.name, entity.value))
        elif isinstance(entity, en.SetParametersFromFile):
            if self.gate(entity, scope)[0]:
                scope.global_parameters.append((None, entity.filename))
        elif isinstance(entity, en.SetRemap):
            if self.gate(entity, scope)[0]:
                scope.remaps.append((entity.src, entity.dst))
        elif isinstance(entity, en.AppendEnvironmentVariable | en.EnvironmentStack
                        | en.UnsetLaunchConfiguration):
            if self.gate(entity, scope)[0]:
                apply_scope_action(entity, scope)
        else:
            where = getattr(entity, "origin", None)
            self.warnings.append(f"{where or scope.launch_file}: ignored {entity!r}, which "
                                 "tuilaunch does not know how to run")

    # --- groups and triggers ---------------------------------------------------------------

    def group(self, group: en.Group, outer: Scope, parent: TreeItem) -> None:
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
            scope.trigger = self.events.when_trigger(group.when, scope)
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

    # --- includes and opaque functions -----------------------------------------------------

    def include(self, include: en.IncludeLaunchDescription, outer: Scope, parent: TreeItem)\
            -> None:
        enabled, skipped = self.gate(include, outer)
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
                given = self.cli_arguments.get(key)
                if given is not None and given != value:
                    # as in ros2 launch the include's value wins there: said, not hidden
                    where = f"{include.origin}: " if include.origin else ""
                    self.warnings.append(
                        f"{where}the include of {os.path.basename(path)} passes {key}:="
                        f"{value}, which overrides {key}:={given} from the command line "
                        "in that file")
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
        if enabled:
            scope.env.update(loaded.environ)  # its module code's os.environ writes
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
        if not self.gate(entity, scope)[0]:
            return
        produced, environ = perform_opaque(entity, scope.context())
        scope.env.update(environ)
        self.walk(produced, scope, parent)

    # --- processes -------------------------------------------------------------------------

    def process(self, entity: en.Node | en.ExecuteProcess, scope: Scope, parent: TreeItem) -> None:
        enabled, skipped = self.gate(entity, scope)
        counter = self._counter
        try:
            plan = self.process_planner.plan(entity, scope, enabled, skipped)
        except LaunchError as exc:
            self._counter = counter  # the number the failed attempt took is this one's
            # what is not installed (a package, FindExecutable's program) fails the process
            # that needs it, and the rest runs; any other mistake in an enabled one stops
            if enabled and not isinstance(exc, PackageError):
                raise
            plan = self.process_planner.failed(entity, scope, exc, enabled, skipped)
        plan.source = entity
        self.processes.append(plan)
        self.entity_ids[id(entity)] = plan.id
        if getattr(entity, "lifecycle", False):
            self.lifecycle_entities[plan.id] = entity
        parent.children.append(TreeItem("process", plan.label, enabled, plan.namespace,
                                        skipped, scope.trigger, plan.id))
        if entity.on_exit is not None:
            self.events.on_exit(entity, scope, parent)

    # --- actions ---------------------------------------------------------------------------

    def action(self, entity: Any, scope: Scope, parent: TreeItem) -> None:
        enabled, skipped = self.gate(entity, scope)
        plan, label = self.action_planner.plan(entity, scope, enabled, skipped)
        self.actions.append(plan)
        self.entity_ids[id(entity)] = plan.id
        parent.children.append(TreeItem("action", label, enabled, scope.namespace, skipped,
                                        scope.trigger, plan.id))


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


LAUNCH_OWN = frozenset((*LAUNCH_CONFIGURATIONS, LAUNCH_PREFIX, LAUNCH_PREFIX_FILTER))
"""Configurations launch itself reads (`sigterm_timeout:=10`, `launch-prefix:=...`): given
on the command line without a file declaring them, they are no mistyped argument."""


def undeclared_warning(name: str, declared: set[str], path: str) -> str:
    """A mistyped argument (`robto:=r2`): said, with the declared name it most resembles."""
    import difflib  # paid only when an argument is not declared

    close = difflib.get_close_matches(name, sorted(declared), n=1)
    guess = f"; did you mean '{close[0]}'?" if close else ""
    return (f"argument '{name}' is not declared by {os.path.basename(path)} or its "
            f"includes{guess} (declared: {', '.join(sorted(declared)) or 'none'})")


__all__ = ["Resolver", "declared_arguments", "default_params_dir", "join_namespace",
           "remove_default_params_dir", "resolve"]
