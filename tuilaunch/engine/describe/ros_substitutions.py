"""launch_ros's substitutions: packages through the ament index, `$(param)` and xacro.

They sit apart from the launch ones in substitutions.py because they reach the package index,
the typed parameter values and xacro, which the core substitutions do not need.
"""

from __future__ import annotations

import shlex
from typing import Any

from ..errors import LaunchError, caller_origin
from ..packages import find_executable, package_prefix, package_share
from .substitutions import PerformContext, Substitution, SubValue, describe, perform
from .values import typed_value
from .xacro_run import run_xacro


class _PackagePath(Substitution):
    """A path of a package found in the ament index, when performed or by `find`."""

    tag = ""

    def __init__(self, package: SubValue) -> None:
        self.package = package
        self.origin = caller_origin()

    def locate(self, package_name: str) -> str:
        raise NotImplementedError

    def perform(self, context: PerformContext) -> str:
        return self.locate(perform(self.package, context))

    def find(self, package_name: str) -> str:
        """launch_ros's FindPackageShare.find / FindPackagePrefix.find: files call it while
        they load."""
        return self.locate(package_name)

    def describe(self) -> str:
        return f"$({self.tag} {describe(self.package)})"


class FindPackageShare(_PackagePath):
    tag = "find-pkg-share"

    def locate(self, package_name: str) -> str:
        return str(package_share(package_name, self.origin))


class FindPackagePrefix(_PackagePath):
    tag = "find-pkg-prefix"

    def locate(self, package_name: str) -> str:
        return str(package_prefix(package_name, self.origin))


class ExecutableInPackage(Substitution):
    """launch_ros.substitutions.ExecutableInPackage: the path of a package's executable."""

    def __init__(self, executable: SubValue, package: SubValue) -> None:
        self.executable, self.package = executable, package
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        return str(find_executable(perform(self.package, context),
                                   perform(self.executable, context), self.origin))

    def describe(self) -> str:
        return f"$(exec-in-pkg {describe(self.executable)} {describe(self.package)})"


class ParameterSubstitution(Substitution):
    """launch_ros.substitutions.Parameter, `$(param name [default])`: a value given earlier in
    scope by SetParameter (or `<set_parameter>`)."""

    def __init__(self, name: SubValue, default: SubValue = None) -> None:
        self.name, self.default = name, default
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        name = perform(self.name, context)
        for key, value in context.global_parameters:
            if key is not None and perform(key, context) == name:  # None: a parameter file
                typed = typed_value(value, context, name, self.origin)
                return str(typed).lower() if isinstance(typed, bool) else str(typed)
        if self.default is not None:
            return perform(self.default, context)
        raise LaunchError(f"$(param {name}): no SetParameter named '{name}' comes before",
                          self.origin, hint="set it first (SetParameter, <set_parameter "
                          "name= value=>), or give a default: $(param name default)")

    def describe(self) -> str:
        return f"$(param {describe(self.name)})"


class Xacro(Substitution):
    """The xacro output of a description file: always a string parameter, never YAML-read."""

    string_typed = True

    def __init__(self, path: SubValue, arguments: list[tuple[Any, Any]]) -> None:
        self.path = path
        self.arguments = arguments
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        return run_xacro(perform(self.path, context), self.mappings(context), self.origin)

    def mappings(self, context: PerformContext) -> dict[str, str]:
        """`name:=value` words as simple_launch's `xacro FILE name:=value ...` command line
        becomes them: split as a shell would, so `rgb:='0 1 0'` gives xacro `0 1 0`."""
        text = " ".join(f"{perform(k, context)}:={perform(v, context)}"
                        for k, v in self.arguments)
        try:
            words = shlex.split(text)
        except ValueError as exc:
            raise LaunchError(f"xacro arguments {text!r} cannot be split as a shell would: "
                              f"{exc}", self.origin) from None
        mappings: dict[str, str] = {}
        for word in words:
            name, sep, value = word.partition(":=")
            if not sep:
                raise LaunchError(
                    f"xacro argument word {word!r} is not name:=value (in {text!r})",
                    self.origin, hint="quote a value that holds spaces: \"'0 1 0'\"")
            mappings[name] = value
        return mappings

    def describe(self) -> str:
        args = " ".join(f"{describe(k)}:={describe(v)}" for k, v in self.arguments)
        return f"$(xacro {describe(self.path)}{' ' + args if args else ''})"
