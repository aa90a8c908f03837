"""launch_ros's parameter descriptions: `ParameterFile` (with `allow_substs`) and `Parameter`."""

from __future__ import annotations

import re
from typing import Any

from ..errors import LaunchError, caller_origin
from .ros_substitutions import FindPackagePrefix, FindPackageShare
from .substitutions import (
    EnvironmentVariable,
    LaunchConfiguration,
    PerformContext,
    SubValue,
    describe,
    perform,
)


class ParameterFile:
    """A node's parameter file; with allow_substs, `$(var x)` inside it is performed first."""

    def __init__(self, param_file: SubValue, *, allow_substs: Any = False) -> None:
        self.param_file = param_file
        self.allow_substs = allow_substs
        self.origin = caller_origin()

    def path(self, context: PerformContext) -> str:
        return perform(self.param_file, context)

    def substitutes(self, context: PerformContext) -> bool:
        value = self.allow_substs
        return value if isinstance(value, bool) else perform(value, context).lower() == "true"

    def describe(self) -> str:
        return describe(self.param_file)


class Parameter:
    """launch_ros.descriptions.Parameter: one name and value for a node's `parameters`."""

    def __init__(self, name: SubValue, value: Any, *, value_type: Any = None) -> None:
        self.name, self.value, self.value_type = name, value, value_type

    def as_dict(self) -> dict[Any, Any]:
        return {self.name: self.value}


_SUBST = re.compile(r"\$\((var|env|optenv|find-pkg-share|find-pkg-prefix)\s+([^)\s]+)"
                    r"(?:\s+([^)]*))?\)")


def substitute_text(text: str, context: PerformContext, origin: Any) -> str:
    """`$(var name)`, `$(env NAME)`, `$(find-pkg-share pkg)` in a parameter file's text."""

    def one(match: re.Match[str]) -> str:
        kind, name, rest = match.group(1), match.group(2), match.group(3)
        if kind == "var":
            return LaunchConfiguration(name).perform(context)
        if kind in ("env", "optenv"):
            default = rest if rest is not None else ("" if kind == "optenv" else None)
            return EnvironmentVariable(name, default_value=default).perform(context)
        if kind == "find-pkg-share":
            return FindPackageShare(name).perform(context)
        return FindPackagePrefix(name).perform(context)

    try:
        return _SUBST.sub(one, text)
    except LaunchError as exc:
        raise LaunchError(f"in a parameter file with allow_substs: {exc.message}",
                          origin) from None


def dotted(tree: dict[Any, Any], prefix: str = "") -> dict[str, Any]:
    """Nested mappings as dotted names: `{"a": {"b": 1}}` -> `{"a.b": 1}` (a parameter
    file's section, a service request's fields)."""
    out: dict[str, Any] = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            out.update(dotted(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def node_sections(loaded: dict[Any, Any], keys: tuple[str, ...] = ()) -> dict[str, dict[str, Any]]:
    """Every `ros__parameters` block of a parameter file, by the node key above it
    (`ns/node`, no leading slash; `**` for every node)."""
    found: dict[str, dict[str, Any]] = {}
    for key, value in loaded.items():
        if key == "ros__parameters":
            if isinstance(value, dict):
                found["/".join(keys)] = value
            continue
        if isinstance(value, dict):
            found.update(node_sections(value, (*keys, str(key).strip("/"))))
    return found

