"""xacro, run in-process at resolve time for `robot_state_publisher` descriptions."""

from __future__ import annotations

import io
from contextlib import redirect_stderr

from ..errors import LaunchError, Origin


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
