"""A process's command line, as ros2 launch builds it: an ExecuteProcess's cmd, and a Node's
`[prefix] exe args [--ros-args ros_args] --ros-args -r __node:= -r __ns:= -p/--params-file
... -r from:=to`, with its environment, respawn and parameter files."""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ...describe.conditions import ConditionOutcome
from ...describe.entities import ExecuteProcess, Node, pair_list
from ...describe.parameter_files import Parameter, ParameterFile, substitute_text
from ...describe.substitutions import (
    PerformContext,
    describe,
    perform,
    perform_optional,
    text_to_bool,
)
from ...describe.values import ParamValue, flatten_parameters
from ...errors import LaunchError, Origin, PackageError
from ...packages import find_executable
from ..components import component_plan
from ..model import ProcessPlan
from ..scope import Scope, join_namespace, name_problem, namespace_problem
from .prefix import LAUNCH_PREFIX, LAUNCH_PREFIX_FILTER, final_cmd

_FIND_EXEC = re.compile(r"\$\((?:find-exec|exec-in-pkg) ([^ )]+)[^)]*\)")
DEFAULT_RESPAWN_MAX_RETRIES = -1  # as launch: respawn for as long as the launch runs


def _seconds(value: Any, ctx: PerformContext, what: str, origin: Origin | None) -> float:
    text = perform(value, ctx)
    try:
        return float(text)
    except ValueError:
        raise LaunchError(f"{what} {text!r} is not a number of seconds", origin) from None


def _float_or_none(value: Any, ctx: PerformContext, what: str, origin: Origin | None)\
        -> float | None:
    return None if value is None else _seconds(value, ctx, what, origin)


LAUNCH_CONFIGURATIONS = ("sigterm_timeout", "sigkill_timeout", "emulate_tty")
"""launch's own configurations a process reads when it does not say (ExecuteLocal):
`sigterm_timeout:=10` on the command line sets every process's."""


def _timeout(value: Any, what: str, ctx: PerformContext, scope: Scope,
             origin: Origin | None) -> float | None:
    """The process's own, else launch's default `LaunchConfiguration(what, default=5)`."""
    if value is None:
        value = scope.configurations.get(what)
    return _float_or_none(value, ctx, what, origin)


def _emulate_tty(entity: ExecuteProcess | Node, ctx: PerformContext, scope: Scope)\
        -> bool | None:
    """The `emulate_tty` launch configuration, when set, overrides the process's own, as
    in launch; None: a terminal when its output is shown (tuilaunch's default)."""
    given = scope.configurations.get("emulate_tty", getattr(entity, "emulate_tty", None))
    return None if given is None else bool(text_to_bool(perform(given, ctx)))


def _rule_text(value: ParamValue) -> str:
    """A SetParameter value as launch_ros writes it after `-p name:=`: Python's str."""
    return str(value)


def _yaml_rule_text(value: ParamValue) -> str:
    """A launch_ros Parameter's value after `-p name:=`: YAML, so text stays text."""
    import yaml

    return str(yaml.safe_dump(value))


def as_list(value: Any) -> list[Any]:
    if value is None:
        return []
    if isinstance(value, list | tuple):
        return list(value)
    return [value]


def _first_program(cmd: Any) -> Any:
    """The program of an ExecuteProcess cmd (to name a process that could not resolve)."""
    items = as_list(cmd) if cmd is not None else []
    return items[0] if items else None


class ProcessPlanner:
    """Turns a Node or ExecuteProcess, in its scope, into a ProcessPlan.

    `next_id` numbers processes for the whole plan; parameter files are written under
    `params_dir`; what does not stop the launch (a missing parameter file) goes to `warnings`."""

    def __init__(self, next_id: Callable[[str], str], params_dir: Path,
                 warnings: list[str]) -> None:
        self.next_id = next_id
        self.params_dir = params_dir
        self._params_folder = str(params_dir)  # joined as text: once per node of the plan
        self._executables: dict[tuple[str, str], str | PackageError] = {}
        """`find_executable` per (package, executable) for this plan: a fleet of 1000 nodes
        names a handful of programs, and each look-up costs two stats."""
        self._on_path: dict[tuple[str, str | None], bool] = {}
        """Whether a command is found on PATH, per (command, PATH): 100 `sleep`s are one
        search of PATH, not 100."""
        self.warnings = warnings

    def found_on_path(self, command: str) -> bool:
        key = (command, os.environ.get("PATH"))
        found = self._on_path.get(key)
        if found is None:
            found = self._on_path[key] = shutil.which(command) is not None
        return found

    def plan(self, entity: Node | ExecuteProcess, scope: Scope, enabled: bool,
                      skipped: ConditionOutcome | None) -> ProcessPlan:
        ctx = scope.context()
        env = {k: v for k, v in scope.env.items() if v is not None}
        if entity.additional_env:
            env.update({perform(k, ctx): perform(v, ctx) for k, v in entity.additional_env.items()})
        clear_env = entity.env is not None
        # launch builds the child's environment from os.environ after the unset: the
        # process does not inherit it (unless its additional_env sets it again)
        unset_env = sorted(k for k, v in scope.env.items() if v is None and k not in env)
        if entity.env is not None:
            env = {perform(k, ctx): perform(v, ctx) for k, v in entity.env.items()}
            unset_env = []
        own_prefix = perform(entity.prefix, ctx) if entity.prefix is not None else None
        launch_prefix = scope.configurations.get(LAUNCH_PREFIX) or ""
        prefix_filter = scope.configurations.get(LAUNCH_PREFIX_FILTER) or ""

        def prefix(cmd: list[str]) -> list[str]:
            """Its own prefix, else launch-prefix where launch-prefix-filter matches."""
            return final_cmd(cmd, own_prefix, launch_prefix, prefix_filter)

        respawn = text_to_bool(perform(entity.respawn, ctx)) or False
        respawn_delay = _seconds(entity.respawn_delay, ctx, "respawn_delay", entity.origin) \
            if entity.respawn_delay is not None else 0.0
        retries = entity.respawn_max_retries
        common = dict(
            env=env, unset_env=unset_env, clear_env=clear_env,
            cwd=perform_optional(entity.cwd, ctx),
            respawn=respawn, respawn_delay=respawn_delay,
            respawn_max_retries=DEFAULT_RESPAWN_MAX_RETRIES if retries is None else retries,
            sigterm_timeout=_timeout(entity.sigterm_timeout, "sigterm_timeout", ctx, scope,
                                     entity.origin),
            sigkill_timeout=_timeout(entity.sigkill_timeout, "sigkill_timeout", ctx, scope,
                                     entity.origin),
            **output_settings(entity, ctx),
            log_cmd=bool(getattr(entity, "log_cmd", False)),
            output_format=getattr(entity, "output_format", None),
            emulate_tty=_emulate_tty(entity, ctx, scope),
            enabled=enabled, skipped_by=skipped, trigger=scope.trigger, origin=entity.origin,
        )
        if isinstance(entity, ExecuteProcess):
            return self._execute_process_plan(entity, ctx, scope, prefix, common)
        return self._node_plan(entity, ctx, scope, prefix, common)

    def _execute_process_plan(self, entity: ExecuteProcess, ctx: PerformContext, scope: Scope,
                              prefix: Callable[[list[str]], list[str]],
                              common: dict[str, Any]) -> ProcessPlan:
        cmd = [perform(part, ctx) for part in as_list(entity.cmd)]
        cmd = [c for c in cmd if c != ""]
        if not cmd:
            raise LaunchError("ExecuteProcess with an empty cmd", entity.origin)
        started = prefix(cmd)
        if entity.shell:
            cmd = ["/bin/sh", "-c", " ".join(cmd)]
            started = ["/bin/sh", "-c", " ".join(started)]
        name = perform_optional(entity.name, ctx)
        base = name or os.path.basename(cmd[0].split()[0])
        error = None
        if not entity.shell and "/" not in cmd[0] and not self.found_on_path(cmd[0]):
            error = f"command '{cmd[0]}' not found on PATH"
        return ProcessPlan(self.next_id(base), "process", name, scope.namespace, None, cmd[0],
                           started, {}, [], [], [], error=error, **common)

    def _node_plan(self, entity: Node, ctx: PerformContext, scope: Scope,
                   prefix: Callable[[list[str]], list[str]],
                   common: dict[str, Any]) -> ProcessPlan:
        package = perform_optional(entity.package, ctx)
        executable = perform(entity.executable, ctx)
        name = perform_optional(entity.name, ctx) or None
        own_namespace = perform_optional(entity.namespace, ctx)
        namespace = join_namespace(scope.namespace, own_namespace)
        # the node's name when it has one: `[monitor-5]` says more than `[listener-5]`
        proc_id = self.next_id(name or os.path.basename(executable))
        error = (name_problem(name) if name else None) or namespace_problem(namespace)
        exe_path = executable
        if package is not None:
            found = self._executables.get((package, executable))
            if found is None:
                try:
                    found = str(find_executable(package, executable, entity.origin))
                except PackageError as exc:
                    found = exc
                self._executables[(package, executable)] = found
            if isinstance(found, PackageError):
                error = error or found.message
            else:
                exe_path = found
        elif not self.found_on_path(executable):
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
        items += [("own", item) for item in as_list(entity.parameters)]
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
        arguments = [perform(a, ctx) for a in as_list(entity.arguments)]
        ros_arguments = [perform(a, ctx) for a in as_list(entity.ros_arguments)]
        # launch_ros: the user's ros_arguments in a block of their own, then always a
        # `--ros-args` block for the name, namespace, parameters and remappings
        cmd = [exe_path, *arguments]
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
        cmd = prefix(cmd)
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
        path = os.path.join(self._params_folder, f"{proc_id}{suffix}.yaml")
        params_args += ["--params-file", path]
        return path, dict(params)

    def failed(self, entity: Node | ExecuteProcess, scope: Scope, exc: LaunchError,
               enabled: bool, skipped: ConditionOutcome | None) -> ProcessPlan:
        """The plan of a process that could not resolve: named, numbered, with its error."""
        program = describe(getattr(entity, "executable", None)
                           or _first_program(getattr(entity, "cmd", None)) or "process")
        # `$(find-exec ros2)` names its process `ros2`
        base = os.path.basename(_FIND_EXEC.sub(r"\1", program)) or "process"
        given = getattr(entity, "name", None)
        name = given if isinstance(given, str) and given else None
        plan = ProcessPlan(self.next_id(name or base), entity.kind, name, scope.namespace,
                           None,
                           base, [], {}, [], [], [], {}, False, None, False, 0.0, 0, None,
                           None, enabled, skipped, scope.trigger, entity.origin,
                           error=exc.message if enabled else f"not resolved: {exc.message}")
        return plan


_SHOWN = {"screen": ("stdout", "stderr"), "both": ("stdout", "stderr"),
          "full": ("stdout", "stderr"), "log": ("stderr",), "own_log": ()}
"""launch.logging's output aliases: the streams each puts on the screen."""


def output_settings(entity: ExecuteProcess | Node, ctx: PerformContext) -> dict[str, Any]:
    """`output` as launch reads it (OVERRIDE_LAUNCH_PROCESS_OUTPUT, when set, for every
    process), and the streams it shows on the screen (launch.logging's
    get_output_loggers). Without one, both streams are shown, as with `'screen'`."""
    given = os.environ.get("OVERRIDE_LAUNCH_PROCESS_OUTPUT", entity.output)
    if given is None:
        return {"output": "screen", "screen": _SHOWN["screen"]}
    if isinstance(given, dict):
        shown: set[str] = set()
        for source, destinations in given.items():
            if source not in ("stdout", "stderr", "both"):
                raise LaunchError(f"output: {source!r} is not an output source (stdout, "
                                  "stderr or both)", entity.origin)
            wanted = {destinations} if isinstance(destinations, str) else set(destinations)
            for destination in wanted - {"screen", "log", "own_log"}:
                raise LaunchError(f"output: {destination!r} is not an output destination "
                                  "(screen, log or own_log)", entity.origin)
            if "screen" in wanted:
                shown |= {"stdout", "stderr"} if source == "both" else {source}
        return {"output": "log", "screen": tuple(s for s in ("stdout", "stderr") if s in shown)}
    text = str(perform(given, ctx))
    if text not in _SHOWN:
        if given is not entity.output:  # the environment's, not the file's
            raise LaunchError(f"OVERRIDE_LAUNCH_PROCESS_OUTPUT={text!r} is not one of "
                              "screen, log, both, own_log, full")
        raise LaunchError(f"output '{text}' is not one of screen, log, both, own_log, full",
                          entity.origin)
    return {"output": text, "screen": _SHOWN[text]}
