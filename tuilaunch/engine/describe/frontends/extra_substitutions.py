"""Substitutions the frontends offer that the Python side of the engine had no class for."""

from __future__ import annotations

import os

from ...errors import LaunchError
from ..substitutions import PerformContext, Substitution, SubValue, describe, perform


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
