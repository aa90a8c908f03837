"""Substitutions the frontends' actions make (`<append_env>`, `<param from= allow_substs=>`)
that the Python side of the engine had no class for."""

from __future__ import annotations

import atexit
import os
import shutil
import tempfile
from dataclasses import dataclass

from ...errors import LaunchError, Origin
from ..substitutions import (
    PerformContext,
    Substitution,
    SubValue,
    describe,
    perform,
    text_to_bool,
)
from .subst_parser import SubstitutionSyntaxError, parse_substitutions


@dataclass(eq=False, repr=False)  # a Substitution's own equality and repr
class AppendedEnvironment(Substitution):
    """The value `<append_env>` gives a variable: the old value, a separator, the new one."""

    name: SubValue
    value: SubValue
    prepend: SubValue
    separator: SubValue

    def perform(self, context: PerformContext) -> str:
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
        import hashlib  # OpenSSL's libcrypto: megabytes of memory, only for the files that ask

        content = perform(parts, context)
        digest = hashlib.sha1(f"{path}\0{content}".encode()).hexdigest()[:16]
        out = os.path.join(_SUBSTITUTED_DIR, f"{os.path.basename(path)}.{digest}.yaml")
        os.makedirs(_SUBSTITUTED_DIR, exist_ok=True)
        with open(out, "w", encoding="utf-8") as handle:
            handle.write(content)
        return out

    def describe(self) -> str:
        return f"{describe(self.path)} (with substitutions)"
