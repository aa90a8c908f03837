"""The Plan: what will happen for one set of argument values, as plain data.

A Plan can be printed as JSON, diffed against another, and tested without starting
anything. The supervisor runs it; the UI draws its tree.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

from ..describe.conditions import ConditionOutcome
from ..describe.entities import TriggerOn
from ..errors import Origin
from ..packages import ENVIRONMENT_CHANGES


@dataclass
class Trigger:
    """What starts an item: an event on another process or action, then a delay."""

    on: TriggerOn
    target: str | None = None
    delay: float = 0.0
    io: str | None = None
    after: Trigger | None = None
    target_entity: Any = field(default=None, repr=False, compare=False)
    repeat: bool = False  # a state trigger: fires on every matching transition, not once

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"on": self.on, "target": self.target, "delay": self.delay}
        if self.io:
            out["io"] = self.io
        if self.after is not None:
            out["after"] = self.after.to_json()
        return out

    def describe(self) -> str:
        who = self.target or "any process"
        event = {
            TriggerOn.START: f"{who} starts",
            TriggerOn.EXIT: f"{who} exits",
            TriggerOn.IO: f"{who} prints on {self.io}",
            TriggerOn.TIMER: "launch",
            TriggerOn.SHUTDOWN: "shutdown",
            TriggerOn.STATE: f"{'a lifecycle node' if self.target == '*' else self.target} reaches "
                     f"{_state_text(self.io)}",
        }[self.on]
        if self.on == TriggerOn.TIMER and self.after is not None:
            # a delay nested in an event group counts from that event
            outer = self.after.describe().removeprefix("when ")
            return f"{self.delay:g} s after {outer}" if self.delay else f"when {outer}"
        text = f"{self.delay:g} s after {event}" if self.delay else f"when {event}"
        if self.after is not None:
            text += f", armed {self.after.describe()}"
        return text


def _state_text(io: str | None) -> str:
    """`configure|*|inactive` (a lifecycle state trigger's filter) as words."""
    transition, start, goal = [*(io or "*|*|*").split("|"), "*", "*"][:3]
    parts = [goal if goal != "*" else "a state"]
    if start != "*":
        parts.append(f"from {start}")
    if transition != "*":
        parts.append(f"by {transition}")
    return " ".join(parts)


@dataclass
class ArgumentInfo:
    name: str
    default: str | None
    value: str | None
    description: str | None
    choices: list[str] | None
    type: str
    file: str
    line: int | None
    elsewhere: list[str] = field(default_factory=list)
    """Other values the same name has where it is declared again (a file included twice
    with other arguments): `'r2' in robot.launch.py:4`, in file order."""

    def to_json(self) -> dict[str, Any]:
        return {"name": self.name, "default": self.default, "value": self.value,
                "description": self.description, "choices": self.choices, "type": self.type,
                "file": self.file, "line": self.line, "elsewhere": self.elsewhere}


@dataclass
class ProcessPlan:
    id: str
    kind: str  # "node" | "process" | "container"
    name: str | None
    namespace: str
    package: str | None
    executable: str
    cmd: list[str]
    parameters: dict[str, Any]
    parameter_files: list[str]
    generated_parameter_files: list[tuple[str, dict[str, Any]]]
    remappings: list[list[str]]
    env: dict[str, str]
    clear_env: bool
    cwd: str | None
    respawn: bool
    respawn_delay: float
    respawn_max_retries: int
    sigterm_timeout: float | None
    sigkill_timeout: float | None
    enabled: bool
    skipped_by: ConditionOutcome | None
    trigger: Trigger | None
    origin: Origin | None
    error: str | None = None
    components: list[dict[str, Any]] = field(default_factory=list)
    output: str = "screen"
    emulate_tty: bool | None = None  # None: a terminal when the output is shown
    screen: tuple[str, ...] = ("stdout", "stderr")
    """The streams a headless run prints, as launch's `output` puts them on the screen
    (`'log'`: stderr only); the log files and the TUI's panes have every line."""
    log_cmd: bool = False  # say the final command line before it starts, as launch does
    output_format: str | None = None
    """launch's `output_format` for the lines a headless run prints (`{line}`, `{this...}`);
    None: `[name] line`."""
    source: Any = field(default=None, repr=False, compare=False)
    """The Node or ExecuteProcess it came from: what `event.action` is in handlers."""
    lifecycle: bool = False
    autostart: bool = False
    machine: str | None = None
    """The machine of a machines file that runs it (`--machines`); None: the launching
    side."""
    unset_env: list[str] = field(default_factory=list)
    """Variables an UnsetEnvironmentVariable in its scope removed: launch starts the process
    from os.environ after the unset, so it does not inherit them."""

    @property
    def full_name(self) -> str | None:
        if self.name is None:
            return None
        return ("" if self.namespace == "/" else self.namespace) + "/" + self.name

    @property
    def label(self) -> str:
        return self.full_name or f"{self.namespace.rstrip('/')}/<{self.executable}>"

    def to_json(self) -> dict[str, Any]:
        return {
            "id": self.id, "kind": self.kind, "name": self.name, "full_name": self.full_name,
            "namespace": self.namespace, "package": self.package, "executable": self.executable,
            "cmd": self.cmd, "parameters": self.parameters,
            "parameter_files": self.parameter_files, "remappings": self.remappings,
            "env": self.env, "unset_env": self.unset_env, "respawn": self.respawn,
            "respawn_delay": self.respawn_delay,
            "enabled": self.enabled,
            "skipped_by": self.skipped_by.to_json() if self.skipped_by else None,
            "trigger": self.trigger.to_json() if self.trigger else None,
            "origin": str(self.origin) if self.origin else None,
            "error": self.error, "components": self.components,
            "lifecycle": self.lifecycle, "autostart": self.autostart,
            "machine": self.machine,
        }


class ActionKind(StrEnum):
    """What an action of the plan does: one member per kind. A StrEnum, so the plan's JSON
    (and a plugin's `actions()` keys) say the same words as before."""

    LOG = "log"  # LogInfo
    CALL_SERVICE = "call_service"
    SET_PARAMETERS = "set_parameters"
    SHUTDOWN = "shutdown"  # Shutdown, EmitEvent(Shutdown())
    STOP_PROCESS = "stop_process"  # EmitEvent(ShutdownProcess(...))
    SIGNAL_PROCESS = "signal_process"  # EmitEvent(SignalProcess(...))
    COROUTINE = "coroutine"  # an OpaqueCoroutine
    LOAD_COMPONENTS = "load_components"  # LoadComposableNodes
    LIFECYCLE_TRANSITION = "lifecycle_transition"  # ChangeState, LifecycleTransition
    EVENT_CALLBACK = "event_callback"  # a handler's callbacks, run when its event comes
    DEFERRED = "deferred"  # what is known only at run time (OpaqueFunction's later part)


@dataclass
class ActionPlan:
    id: str
    kind: ActionKind
    target: str | None
    data: Any
    namespace: str
    verbosity: str
    enabled: bool
    skipped_by: ConditionOutcome | None
    trigger: Trigger | None
    origin: Origin | None
    source: Any = field(default=None, repr=False, compare=False)
    configurations: dict[str, str] = field(default_factory=dict, repr=False, compare=False)
    # the environment changes in scope (name -> value, None: unset): os.environ shows them
    # while the action's launch-time code runs, as in launch
    environ: dict[str, str | None] = field(default_factory=dict, repr=False, compare=False)
    launch_file: str | None = field(default=None, repr=False, compare=False)
    """The file whose visit made it: ThisLaunchFileDir when it is performed at run time."""

    def to_json(self) -> dict[str, Any]:
        return {
            "id": self.id, "kind": self.kind, "target": self.target, "data": self.data,
            "namespace": self.namespace, "verbosity": self.verbosity, "enabled": self.enabled,
            "skipped_by": self.skipped_by.to_json() if self.skipped_by else None,
            "trigger": self.trigger.to_json() if self.trigger else None,
            "origin": str(self.origin) if self.origin else None,
        }


@dataclass
class TreeItem:
    """One row of the group tree: a group, include, process or action, with its children."""

    kind: str  # "group" | "include" | "process" | "action"
    label: str
    enabled: bool
    namespace: str = "/"
    condition: ConditionOutcome | None = None
    trigger: Trigger | None = None
    ref: str | None = None
    children: list[TreeItem] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        return {
            "kind": self.kind, "label": self.label, "enabled": self.enabled,
            "namespace": self.namespace,
            "condition": self.condition.to_json() if self.condition else None,
            "trigger": self.trigger.to_json() if self.trigger else None,
            "ref": self.ref, "children": [c.to_json() for c in self.children],
        }


@dataclass
class Plan:
    file: str
    arguments: list[ArgumentInfo]
    processes: list[ProcessPlan]
    actions: list[ActionPlan]
    tree: TreeItem
    params_dir: Path
    warnings: list[str] = field(default_factory=list)
    entity_ids: dict[int, str] = field(default_factory=dict, repr=False, compare=False)
    """Which process or action each entity became: event-time entities find their targets."""
    id_counter: int = 0
    environ: dict[str, str | None] = field(default_factory=dict, repr=False, compare=False)
    """The launch's environment (changes to tuilaunch's own) as the visit of the whole file
    left it, scoped groups' changes popped: what launch's os.environ is when events happen,
    and what the code run then sees (and changes, for what follows)."""
    """The last number given to a process id; ids made at event time continue from it."""

    def process(self, process_id: str) -> ProcessPlan:
        for proc in self.processes:
            if proc.id == process_id:
                return proc
        raise KeyError(process_id)

    def enabled_processes(self) -> list[ProcessPlan]:
        return [p for p in self.processes if p.enabled]

    def problems(self) -> list[str]:
        """Enabled processes that cannot start: each names the process and why. One placed
        on another machine is checked there (its package need not be installed here)."""
        return [f"{p.origin or self.file}: {p.id} ({p.label}): {p.error}"
                for p in self.processes if p.enabled and p.error and p.machine is None]

    def to_json(self) -> dict[str, Any]:
        return {
            "file": self.file,
            "arguments": [a.to_json() for a in self.arguments],
            "processes": [p.to_json() for p in self.processes],
            "actions": [a.to_json() for a in self.actions],
            "tree": self.tree.to_json(),
            "warnings": self.warnings,
            # what tuilaunch changes on purpose in every child's environment, and why
            "environment_changes": dict(ENVIRONMENT_CHANGES),
        }


def process_signature(proc: ProcessPlan) -> tuple[Any, ...]:
    """What a running process depends on: same signature, no need to restart it."""
    params = tuple((path, repr(sorted(values.items())))
                   for path, values in proc.generated_parameter_files)
    return (tuple(proc.cmd), tuple(sorted(proc.env.items())), tuple(proc.unset_env),
            proc.clear_env, proc.cwd, params, proc.respawn, proc.machine)


@dataclass
class PlanDiff:
    """Which processes a relaunch keeps running, stops, and starts."""

    keep: list[str]
    stop: list[str]
    start: list[str]

    @property
    def empty(self) -> bool:
        return not self.stop and not self.start


def diff_plans(old: Plan, new: Plan, running: set[str] | None = None) -> PlanDiff:
    """Compares enabled processes by id and signature.

    An unchanged process is left as it is, running or not: a one-shot that finished (a
    spawner, a map loader) does not run again, and one that failed waits for the operator's
    restart, as if the relaunch had not touched it. A changed one that is not in `running`
    (None: all are) only starts, as there is nothing to stop."""
    old_enabled = {p.id: p for p in old.processes if p.enabled}
    new_enabled = {p.id: p for p in new.processes if p.enabled}
    alive = set(old_enabled) if running is None else running
    keep: list[str] = []
    stop: list[str] = []
    start: list[str] = []
    for pid, proc in old_enabled.items():
        other = new_enabled.get(pid)
        if other is not None and process_signature(other) == process_signature(proc):
            keep.append(pid)
            continue
        if pid in alive:
            stop.append(pid)
        if other is not None:
            start.append(pid)
    start += [pid for pid in new_enabled if pid not in old_enabled]
    return PlanDiff(keep, stop, start)
