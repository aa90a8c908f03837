"""Lazy values: substitutions performed against the argument values of one resolve.

The same Description is resolved again whenever the operator edits an argument, so nothing
here is evaluated when a launch file is loaded, only in `perform`.
"""

from __future__ import annotations

import math
import os
import shlex
import shutil
import subprocess
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from ..errors import LaunchError, Origin, PackageError, caller_origin
from .xacro_run import run_xacro_argv

SubValue = Any  # str | int | float | bool | Substitution | nested lists of those


class _Locals:
    """`context.locals`: the current event and file, as attributes."""

    def __init__(self, values: dict[str, Any]) -> None:
        self.__dict__.update(values)


@dataclass
class PerformContext:
    """What substitutions may read while a plan is resolved.

    It also offers the part of launch's LaunchContext that extensions call (nav2_common's
    RewrittenYaml, OpaqueFunctions, custom Substitutions), so one object serves both.
    """

    configurations: dict[str, str]
    launch_file: str | None = None
    environment: Mapping[str, str] = field(default_factory=lambda: os.environ)
    event_locals: dict[str, Any] = field(default_factory=dict)
    # (name, value) pairs of SetParameter in scope, for launch_ros's `$(param name)`
    global_parameters: list[tuple[Any, Any]] = field(default_factory=list)
    is_shutdown: bool = False

    @property
    def launch_configurations(self) -> dict[str, str]:
        return self.configurations

    def perform_substitution(self, substitution: Any) -> str:
        return perform(substitution, self)

    def perform_substitutions(self, substitutions: Any) -> str:
        return perform(substitutions, self)

    def get_locals_as_dict(self) -> dict[str, Any]:
        values: dict[str, Any] = {}
        if self.launch_file:
            values["current_launch_file_path"] = self.launch_file
            values["current_launch_file_directory"] = os.path.dirname(self.launch_file)
        values.update(self.event_locals)
        return values

    @property
    def locals(self) -> _Locals:
        return _Locals(self.get_locals_as_dict())

    def extend_locals(self, values: dict[str, Any]) -> None:
        self.event_locals.update(values)

    def extend_globals(self, values: dict[str, Any]) -> None:
        self.event_locals.update(values)

    @property
    def launch_logger(self) -> Any:
        import logging

        return logging.getLogger("launch.user")


class Substitution:
    """A value known only once argument values are: performed to a string."""

    origin: Origin | None = None

    def __init__(self) -> None:
        """Third-party subclasses call super().__init__(): remember where they were made."""
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        raise NotImplementedError

    def describe(self) -> str:
        return type(self).__name__

    def __repr__(self) -> str:
        return self.describe()

    # `+` and `/` exist on every substitution (not only SimpleSubstitution) because users
    # chain sl.arg() results with plain launch substitutions and strings in any order.
    def __add__(self, other: SubValue) -> SimpleSubstitution:
        return SimpleSubstitution(self, other)

    def __radd__(self, other: SubValue) -> SimpleSubstitution:
        return SimpleSubstitution(other, self)

    def __truediv__(self, other: SubValue) -> SimpleSubstitution:
        return slash_join(self, other)

    def __rtruediv__(self, other: SubValue) -> SimpleSubstitution:
        return slash_join(other, self)


def _is_empty(value: SubValue) -> bool:
    if isinstance(value, SimpleSubstitution):
        return all(_is_empty(part) for part in value.parts)
    return value is None or value == ""


def slash_join(left: SubValue, right: SubValue) -> SimpleSubstitution:
    """simple_launch's `/`: a literal '/' between the parts (not os.path.join, so
    `'/model' / robot / '/pose'` keeps both slashes), none next to a part known empty."""
    sep = None if _is_empty(left) or _is_empty(right) else "/"
    return SimpleSubstitution(left, sep, right)


def flatten(value: SubValue) -> list[Any]:
    """Nested lists and tuples of parts into one flat list, dropping None."""
    if type(value) is str:  # the common case first: a plan flattens every text of every node
        return [value]
    if isinstance(value, list | tuple):
        out: list[Any] = []
        for item in value:
            out.extend(flatten(item))
        return out
    return [] if value is None else [value]


def is_lazy(value: SubValue) -> bool:
    return any(isinstance(part, Substitution) for part in flatten(value))


def perform(value: SubValue, context: PerformContext) -> str:
    """Any text-like value (str, number, substitution, list of them) as one string."""
    if type(value) is str:  # most texts of a plan are plain: no generator, no join
        return value
    return "".join(
        _perform_one(part, context) if isinstance(part, Substitution) else _plain_text(part)
        for part in flatten(value)
    )


def _perform_one(part: Substitution, context: PerformContext) -> str:
    if type(part).__module__.startswith(_OUR_PACKAGE):
        return part.perform(context)
    # a Substitution written outside tuilaunch (nav2_common, a user's file): its errors
    # are reported at its own line, never as a traceback
    try:
        result = part.perform(context)
    except LaunchError:
        raise
    except Exception as exc:
        import sys

        from ..errors import origin_outside_tuilaunch

        where = origin_outside_tuilaunch(sys.exc_info()[2]) or part.origin
        raise LaunchError(f"{type(part).__name__}.perform() raised {type(exc).__name__}: {exc}",
                          where) from None
    return result if isinstance(result, str) else str(result)


_OUR_PACKAGE = __name__.split(".")[0] + "."


def perform_optional(value: SubValue, context: PerformContext) -> str | None:
    return None if value is None else perform(value, context)


def describe(value: SubValue) -> str:
    return "".join(
        part.describe() if isinstance(part, Substitution) else _plain_text(part)
        for part in flatten(value)
    )


def _plain_text(value: Any) -> str:
    return str(value)


class TextSubstitution(Substitution):
    def __init__(self, text: str = "") -> None:
        self.text = str(text)

    def perform(self, context: PerformContext) -> str:
        return self.text

    def describe(self) -> str:
        return self.text


class SimpleSubstitution(Substitution):
    """simple_launch's concatenation of parts, with `+` and `/` against anything text-like."""

    def __init__(self, *parts: SubValue) -> None:
        self.parts: list[Any] = flatten(list(parts))

    def perform(self, context: PerformContext) -> str:
        return perform(self.parts, context)

    def describe(self) -> str:
        return describe(self.parts)

    def has_elems(self) -> bool:
        return bool(self.parts)

    def substitutions(self) -> list[Any]:
        return list(self.parts)

    def __add__(self, other: SubValue) -> SimpleSubstitution:
        return SimpleSubstitution(self.parts, other)

    def __radd__(self, other: SubValue) -> SimpleSubstitution:
        return SimpleSubstitution(other, self.parts)

    def __iadd__(self, other: SubValue) -> SimpleSubstitution:
        return self + other


class LaunchConfiguration(Substitution):
    """The value of a launch argument: `sl.arg(name)` and `$(var name)`."""

    def __init__(self, variable_name: SubValue, default: SubValue = None) -> None:
        self.variable_name = variable_name
        self.default = default
        self.origin = caller_origin()

    def name(self, context: PerformContext | None = None) -> str:
        if context is None:
            return describe(self.variable_name)
        return perform(self.variable_name, context)

    def perform(self, context: PerformContext) -> str:
        name = self.name(context)
        if name in context.configurations:
            return context.configurations[name]
        if self.default is not None:
            return perform(self.default, context)
        raise LaunchError(
            f"launch argument '{name}' is used but has no value",
            self.origin,
            hint=f"declare it with sl.declare_arg('{name}', default) or pass {name}:=value",
        )

    def describe(self) -> str:
        return f"$(var {describe(self.variable_name)})"


class EnvironmentVariable(Substitution):
    def __init__(self, name: SubValue, *, default_value: SubValue = None) -> None:
        self.name = name
        self.default_value = default_value
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        name = perform(self.name, context)
        if name in context.environment:
            return context.environment[name]
        if self.default_value is not None:
            return perform(self.default_value, context)
        raise LaunchError(
            f"environment variable '{name}' is not set", self.origin,
            hint=f"export {name}=... or give EnvironmentVariable a default_value",
        )

    def describe(self) -> str:
        return f"$(env {describe(self.name)})"


class PathJoin(Substitution):
    """`/` between substitutions and `PathJoinSubstitution`."""

    def __init__(self, parts: Iterable[SubValue]) -> None:
        self.parts = list(parts)

    def perform(self, context: PerformContext) -> str:
        pieces = [perform(part, context) for part in self.parts]
        return os.path.join(*pieces) if pieces else ""

    def describe(self) -> str:
        return "/".join(describe(part) for part in self.parts)


PathJoinSubstitution = PathJoin


_EVAL_NAMES = {"true": True, "false": False, "True": True, "False": False, "math": math}


class PythonExpression(Substitution):
    """`sl.py_eval` and launch's PythonExpression: parts performed, then evaluated.

    `true`/`false` are accepted as Python booleans because launch arguments come from the
    command line in ROS spelling (`robot1:=true`).
    """

    def __init__(self, expression: SubValue, python_modules: SubValue = None) -> None:
        self.expression = expression
        self.modules = flatten(python_modules) if python_modules is not None else []
        self.origin = caller_origin()

    def evaluate(self, context: PerformContext) -> Any:
        text = perform(self.expression, context)
        names: dict[str, Any] = dict(_EVAL_NAMES)
        for module in self.modules:
            name = perform(module, context)
            names[name] = __import__(name)
        try:
            return eval(text, names)
        except Exception as exc:  # any user expression error must name the expression
            raise LaunchError(
                f"cannot evaluate Python expression {text!r}: {type(exc).__name__}: {exc}",
                self.origin,
                hint="py_eval joins its parts as text: check spaces around and/or/not "
                "and quotes around string values",
            ) from None

    def perform(self, context: PerformContext) -> str:
        return str(self.evaluate(context))

    def describe(self) -> str:
        return f"$(eval {describe(self.expression)!r})"


class Command(Substitution):
    """Output of a command run at resolve time (e.g. `xacro robot.xacro`)."""

    def __init__(self, command: SubValue, on_stderr: SubValue = "fail") -> None:
        self.command = command
        self.on_stderr = on_stderr
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        text = perform(self.command, context)
        argv = shlex.split(text)
        if argv and argv[0] == "xacro" and shutil.which("xacro") is None:
            return run_xacro_argv(argv[1:], self.origin)
        try:
            done = subprocess.run(argv, capture_output=True, text=True, timeout=60)
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise LaunchError(f"command {text!r} could not run: {exc}", self.origin) from None
        mode = perform(self.on_stderr, context)
        if done.returncode != 0 or (done.stderr and mode == "fail"):
            raise LaunchError(
                f"command {text!r} failed (exit {done.returncode}): {done.stderr.strip()}",
                self.origin,
            )
        return done.stdout

    def describe(self) -> str:
        return f"$(command {describe(self.command)!r})"


class FindExecutable(Substitution):
    def __init__(self, *, name: SubValue) -> None:
        self.name = name
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        name = perform(self.name, context)
        found = shutil.which(name)
        if found is None:
            # not installed: the process that needs it fails alone
            raise PackageError(f"executable '{name}' not found on PATH", self.origin)
        return found

    def describe(self) -> str:
        return f"$(find-exec {describe(self.name)})"


class ThisLaunchFile(Substitution):
    def perform(self, context: PerformContext) -> str:
        return _this_launch_file(context, "ThisLaunchFile")

    def describe(self) -> str:
        return "$(filename)"


def _this_launch_file(context: PerformContext, name: str) -> str:
    if context.launch_file is None:  # launch's words: its locals hold no file there
        failure = SubstitutionFailure(f"{name} used outside of a launch file (in a script)")
        failure.origin = None  # performed by the run, not at a user's line: its action says
        raise failure
    return context.launch_file


class ThisLaunchFileDir(Substitution):
    def perform(self, context: PerformContext) -> str:
        return os.path.dirname(_this_launch_file(context, "ThisLaunchFileDir"))

    def describe(self) -> str:
        return "$(dirname)"


class LocalSubstitution(Substitution):
    """A value of the event being handled (e.g. `event.reason`), known only at run time."""

    def __init__(self, expression: str, description: str | None = None) -> None:
        self.expression = expression
        self.description = description

    def perform(self, context: PerformContext) -> str:
        if self.expression.split(".")[0] not in context.event_locals:
            return f"<{self.expression}>"  # resolved into a plan: the event comes later
        value: Any = context.event_locals
        for key in self.expression.split("."):
            if isinstance(value, dict):
                value = value.get(key, "")
            else:
                value = getattr(value, key, "")
        return str(value)

    def describe(self) -> str:
        return f"<{self.expression}>"


class AnonName(Substitution):
    """A name made unique per run, stable within one resolve of the same plan."""

    _names: dict[str, str] = {}

    def __init__(self, name: SubValue) -> None:
        self.name = name

    def perform(self, context: PerformContext) -> str:
        base = perform(self.name, context)
        if base not in self._names:
            import uuid  # platform and all: paid only by a file that uses AnonName

            self._names[base] = f"{base}_{uuid.uuid4().hex[:8]}"
        return self._names[base]

    def describe(self) -> str:
        return f"$(anon {describe(self.name)})"


def text_to_bool(text: str) -> bool | None:
    """ROS launch's reading of a condition string; None when it is not a boolean."""
    lowered = text.strip().lower()
    if lowered in ("true", "1"):
        return True
    if lowered in ("false", "0"):
        return False
    return None


class SubstitutionFailure(LaunchError):
    """launch.substitutions.SubstitutionFailure: what a substitution raises when it cannot."""

    def __init__(self, message: str = "substitution failed", *_: Any) -> None:
        super().__init__(str(message), caller_origin())


class FileContent(Substitution):
    """The text of a file, read when performed."""

    def __init__(self, path: SubValue) -> None:
        self.path = path
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        path = perform(self.path, context)
        try:
            with open(path, encoding="utf-8") as handle:
                return handle.read()
        except (OSError, UnicodeDecodeError) as exc:
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
            raise LaunchError(f"$(file-content): cannot read {path}: {reason}",
                              self.origin) from None

    def describe(self) -> str:
        return f"$(file-content {describe(self.path)})"


class PathSubstitution(Substitution):
    """A path that joins with `/`, as pathlib does (launch's PathSubstitution)."""

    def __init__(self, path: SubValue) -> None:
        self.path = path

    def perform(self, context: PerformContext) -> str:
        return perform(self.path, context)

    def describe(self) -> str:
        return describe(self.path)

    def __truediv__(self, other: SubValue) -> PathSubstitution:  # type: ignore[override]
        return PathSubstitution(PathJoin([self.path, other]))


class LaunchLogDir(Substitution):
    """Where this launch's log files go (`$(launch-log-dir)`)."""

    def perform(self, context: PerformContext) -> str:
        base = context.environment.get("ROS_LOG_DIR") or os.path.join(
            context.environment.get("ROS_HOME") or os.path.expanduser("~/.ros"), "log")
        return base

    def describe(self) -> str:
        return "$(launch-log-dir)"
