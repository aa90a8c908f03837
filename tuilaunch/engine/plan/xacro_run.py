"""xacro, run in-process at resolve time for `robot_state_publisher` descriptions."""

from __future__ import annotations

import io
import shlex
from contextlib import redirect_stderr
from typing import Any

from ..describe.substitutions import PerformContext, Substitution, SubValue, describe, perform
from ..errors import LaunchError, Origin, caller_origin


def run_xacro(path: str, mappings: dict[str, str], origin: Origin | None) -> str:
    try:
        import xacro
    except ImportError:
        raise LaunchError("the xacro package is not installed", origin,
                          hint="pip install xacro") from None
    errors = io.StringIO()
    try:
        with redirect_stderr(errors):
            document = xacro.process_file(path, mappings=mappings)
    except Exception as exc:  # xacro raises many types; all are the user's file at fault
        detail = errors.getvalue().strip()
        raise LaunchError(
            f"xacro failed on {path}: {exc}" + (f" ({detail})" if detail else ""), origin
        ) from None
    return str(document.toprettyxml(indent="  "))


def run_xacro_argv(argv: list[str], origin: Origin | None) -> str:
    """`xacro FILE name:=value ...` as a Command substitution would run it."""
    files = [a for a in argv if ":=" not in a and not a.startswith("-")]
    if not files:
        raise LaunchError("xacro command without a file", origin)
    mappings = dict(a.split(":=", 1) for a in argv if ":=" in a)
    return run_xacro(files[0], mappings, origin)


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
