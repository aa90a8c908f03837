"""DeclareLaunchArgument, resolved: its value from the command line or its default; and
whether a value typed in the Args tab can be used (`check_values`: only choices refuse,
as in launch) or looks unlike its default's type (`type_notes`: a warning, never a
refusal; the command line takes any value, as ros2 launch does)."""

from __future__ import annotations

import os

from ..describe.entities import DeclareLaunchArgument
from ..describe.substitutions import perform_optional, text_to_bool
from ..errors import ArgumentError
from .model import ArgumentInfo
from .scope import Scope


def declare_argument(arguments: dict[str, ArgumentInfo], lenient: bool,
                     decl: DeclareLaunchArgument, scope: Scope) -> None:
    """Give a declared argument its value in the scope and record it for the argument
    form; a required one without a value, or a value outside the choices, stops the
    walk unless `lenient` (--show-args)."""
    ctx = scope.context()
    default = perform_optional(decl.default_value, ctx)
    if decl.name not in scope.configurations and default is not None:
        scope.configurations[decl.name] = default
    value = scope.configurations.get(decl.name)
    known = arguments.get(decl.name)
    if known is None:
        arguments[decl.name] = ArgumentInfo(
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
    if lenient:
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


def check_values(arguments: list[ArgumentInfo], values: dict[str, str]) -> str | None:
    """Why a typed value cannot be used for its argument, or None: only a value outside
    its choices, which DeclareLaunchArgument refuses too. A value unlike the default's type
    is no reason: launch arguments are strings (`x:=3.5` for a default of 1 is passed as
    written by ros2 launch); `type_notes` says so instead."""
    types = {a.name: a for a in arguments}
    for name, text in values.items():
        arg = types.get(name)
        if arg is not None and arg.choices and text not in arg.choices:
            return f"argument '{name}' must be one of {', '.join(arg.choices)}, got {text!r}"
    return None


def type_notes(arguments: list[ArgumentInfo], values: dict[str, str]) -> list[str]:
    """Values unlike their default's type (a fraction for a default of 1, a word for a
    number, neither true nor false for a boolean): the Args tab warns, as a typing slip is
    likely, and passes them as written, as ros2 launch does."""
    types = {a.name: a for a in arguments}
    notes = []
    for name, text in values.items():
        arg = types.get(name)
        if arg is None or arg.choices:
            continue
        like = None
        if arg.type == "int":
            try:
                int(text.strip())
            except ValueError:
                like = "a whole number"
        elif arg.type == "float":
            try:
                float(text.strip())
            except ValueError:
                like = "a number"
        elif arg.type == "bool" and text_to_bool(text) is None:
            like = "true or false"
        if like is not None:
            notes.append(f"argument '{name}' = {text!r} is not {like} like its default "
                         f"{arg.default}")
    return notes
