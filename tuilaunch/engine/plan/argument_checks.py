"""Whether a value typed for a launch argument suits its type: the Args tab checks each edit
with it, and the command line each name:=value, in the same words."""

from __future__ import annotations

from ..describe.substitutions import text_to_bool
from .model import ArgumentInfo


def check_values(arguments: list[ArgumentInfo], values: dict[str, str]) -> str | None:
    """Why a typed value cannot be used for its argument's type, or None."""
    types = {a.name: a for a in arguments}
    for name, text in values.items():
        arg = types.get(name)
        if arg is None:
            continue
        if arg.choices and text not in arg.choices:
            return f"argument '{name}' must be one of {', '.join(arg.choices)}, got {text!r}"
        if arg.type == "int":
            try:
                int(text.strip())
            except ValueError:
                return f"argument '{name}' needs a whole number, got {text!r}"
        elif arg.type == "float":
            try:
                float(text.strip())
            except ValueError:
                return f"argument '{name}' needs a number, got {text!r}"
        elif arg.type == "bool" and text_to_bool(text) is None:
            return f"argument '{name}' needs true or false, got {text!r}"
    return None
