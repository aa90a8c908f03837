"""Substitutions the frontends offer that the Python side of the engine had no class for."""

from __future__ import annotations

import atexit
import hashlib
import os
import shutil
import tempfile

from ...errors import LaunchError, Origin
from ..substitutions import (
    LaunchConfiguration,
    PerformContext,
    Substitution,
    SubValue,
    describe,
    perform,
)


class ExecutableInPackage(Substitution):
    """`$(exec-in-pkg EXE PKG)`: the path of an executable in a package's lib folder."""

    def __init__(self, executable: SubValue, package: SubValue) -> None:
        self.executable = executable
        self.package = package

    def perform(self, context: PerformContext) -> str:
        from ...plan.packages import find_executable

        return str(find_executable(perform(self.package, context),
                                   perform(self.executable, context), self.origin))

    def describe(self) -> str:
        return f"$(exec-in-pkg {describe(self.executable)} {describe(self.package)})"


class FileContent(Substitution):
    """`$(file-content PATH)`: a file's text, read when the plan is resolved."""

    def __init__(self, path: SubValue) -> None:
        self.path = path

    def perform(self, context: PerformContext) -> str:
        path = perform(self.path, context)
        try:
            with open(path, encoding="utf-8") as handle:
                return handle.read()
        except (OSError, UnicodeDecodeError) as exc:
            raise LaunchError(f"$(file-content): cannot read {path}: {exc}", self.origin)\
                from None

    def describe(self) -> str:
        return f"$(file-content {describe(self.path)})"


class AppendedEnvironment(Substitution):
    """The value `<append_env>` gives a variable: the old value, a separator, the new one."""

    def __init__(self, name: SubValue, value: SubValue, prepend: SubValue,
                 separator: SubValue) -> None:
        self.name = name
        self.value = value
        self.prepend = prepend
        self.separator = separator

    def perform(self, context: PerformContext) -> str:
        from ..substitutions import text_to_bool

        value = perform(self.value, context)
        current = context.environment.get(perform(self.name, context))
        if not current:
            return value
        separator = perform(self.separator, context)
        if text_to_bool(perform(self.prepend, context)):
            return value + separator + current
        return current + separator + value

    def describe(self) -> str:
        return f"${describe(self.name)}{describe(self.separator)}{describe(self.value)}"


def default_path_separator() -> str:
    return os.pathsep


_SUBSTITUTED_DIR = os.path.join(tempfile.gettempdir(), f"tuilaunch-{os.getpid()}-substs")


def _remove_substituted_files() -> None:
    shutil.rmtree(_SUBSTITUTED_DIR, ignore_errors=True)


atexit.register(_remove_substituted_files)


class SubstitutedParameterFile(Substitution):
    """`<param from="f.yaml" allow_substs="true"/>`: the file with its `$(...)` performed.

    Performs to the path of a copy with every substitution replaced, as launch_ros hands the
    node a rewritten file; without allow_substs it is the file's own path.
    """

    def __init__(self, path: SubValue, allow: SubValue) -> None:
        self.path = path
        self.allow = allow

    def perform(self, context: PerformContext) -> str:
        from ..substitutions import text_to_bool
        from .subst_parser import SubstitutionSyntaxError, parse_substitutions

        path = perform(self.path, context)
        if not text_to_bool(perform(self.allow, context)):
            return path
        try:
            with open(path, encoding="utf-8") as handle:
                text = handle.read()
        except (OSError, UnicodeDecodeError) as exc:
            raise LaunchError(f"parameter file {path} cannot be read: {exc}", self.origin)\
                from None
        try:
            parts = parse_substitutions(text, self.origin)
        except SubstitutionSyntaxError as exc:
            line = text.count("\n", 0, exc.offset) + 1
            column = exc.offset - (text.rfind("\n", 0, exc.offset) + 1) + 1
            raise LaunchError(f"{exc.message} (parameter file with allow_substs)",
                              Origin(path, line, column)) from None
        content = perform(parts, context)
        digest = hashlib.sha1(f"{path}\0{content}".encode()).hexdigest()[:16]
        out = os.path.join(_SUBSTITUTED_DIR, f"{os.path.basename(path)}.{digest}.yaml")
        os.makedirs(_SUBSTITUTED_DIR, exist_ok=True)
        with open(out, "w", encoding="utf-8") as handle:
            handle.write(content)
        return out

    def describe(self) -> str:
        return f"{describe(self.path)} (with substitutions)"


class GlobalParameter(Substitution):
    """launch_ros's `$(param name [default])`: a value set earlier by `<set_parameter>`."""

    def __init__(self, name: SubValue, default: SubValue = None) -> None:
        self.name = name
        self.default = default

    def perform(self, context: PerformContext) -> str:
        from ...plan.params import typed_value

        name = perform(self.name, context)
        for key, value in context.global_parameters:
            if key is not None and perform(key, context) == name:  # None: a parameter file
                return str(typed_value(value, context, name, self.origin))
        if self.default is not None:
            return perform(self.default, context)
        raise LaunchError(f"$(param {name}): no <set_parameter> named '{name}' comes before",
                          self.origin, hint="set it with <set_parameter name= value=> first, "
                          "or give a default: $(param name default)")

    def describe(self) -> str:
        return f"$(param {describe(self.name)})"


class FrontendVariable(LaunchConfiguration):
    """`$(var name)`: a LaunchConfiguration whose hint speaks XML/YAML."""

    def perform(self, context: PerformContext) -> str:
        try:
            return super().perform(context)
        except LaunchError as exc:
            name = self.name(context)
            raise LaunchError(exc.message, exc.origin,
                              hint=f'declare it with <arg name="{name}" default="..."/> '
                              f"or pass {name}:=value") from None
