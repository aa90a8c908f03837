"""Errors the operator can cause, each carrying where it happened.

Every message a user sees names the launch file and line, the argument, package or node at
fault, and what would fix it. Tracebacks are for `--debug` only.
"""

from __future__ import annotations

import contextlib
import functools
import os
import sys
import traceback
from dataclasses import dataclass
from types import TracebackType

_ENGINE_DIR = os.path.dirname(os.path.abspath(__file__))
_PACKAGE_DIR = os.path.dirname(_ENGINE_DIR)


@dataclass(frozen=True)
class Origin:
    """A place in a user's launch file: where an entity was written."""

    file: str
    line: int
    column: int | None = None  # XML/YAML errors point at the tag or key, not only its line

    def __str__(self) -> str:
        where = f"{display_path(self.file)}:{self.line}"
        return where if self.column is None else f"{where}:{self.column}"


def display_path(path: str) -> str:
    """Relative to the working directory when below it: what the user typed, mostly."""
    try:
        relative = os.path.relpath(path)
    except ValueError:
        return path
    return path if relative.startswith("..") else relative


_SKIPPED_FILES = {os.path.abspath(contextlib.__file__)}


@functools.lru_cache(maxsize=1024)  # asked for every frame of every entity made
def _is_ours(filename: str) -> bool:
    """Frames of tuilaunch itself, or of the `with` machinery between the user and us."""
    path = os.path.abspath(filename)
    return path.startswith(_PACKAGE_DIR + os.sep) or path in _SKIPPED_FILES


def caller_origin() -> Origin | None:
    """The innermost stack frame outside tuilaunch: the user's line that made this call."""
    frame = sys._getframe(1)
    while frame is not None:
        filename = frame.f_code.co_filename
        if not _is_ours(filename) and not filename.startswith("<frozen"):
            return Origin(filename, frame.f_lineno)
        frame = frame.f_back  # type: ignore[assignment]
    return None


def origin_from_traceback(tb: TracebackType | None, files: set[str]) -> Origin | None:
    """The innermost traceback frame that lies in one of the given launch files."""
    found: Origin | None = None
    for frame_summary in traceback.extract_tb(tb):
        if os.path.abspath(frame_summary.filename) in files:
            found = Origin(frame_summary.filename, frame_summary.lineno or 0)
    return found


class LaunchError(Exception):
    """A problem with the launch file or its arguments, reported without a traceback."""

    def __init__(self, message: str, origin: Origin | None = None, hint: str | None = None):
        super().__init__(message)
        self.message = message
        self.origin = origin
        self.hint = hint

    def __str__(self) -> str:
        where = f"{self.origin}: " if self.origin else ""
        text = f"{where}{self.message}"
        if self.hint:
            text += f"\n  hint: {self.hint}"
        return text


class ArgumentError(LaunchError):
    """A launch argument value that cannot be used (not in choices, not a boolean, unknown)."""


class PackageError(LaunchError):
    """A package, launch file or executable that the ament index does not know."""


class DslError(LaunchError):
    """A SimpleLauncher or launch API call with arguments it cannot take."""


def _stdlib_dirs() -> tuple[str, ...]:
    import sysconfig

    paths = sysconfig.get_paths()
    return tuple(os.path.abspath(paths[key]) + os.sep for key in ("stdlib", "platstdlib"))


def origin_outside_tuilaunch(tb: TracebackType | None) -> Origin | None:
    """The innermost frame of code that is neither tuilaunch nor the standard library.

    That is the line at fault when a user's or a third-party extension's code raises
    (nav2_common's RewrittenYaml reading a params file, a custom Substitution, ...)."""
    stdlib = _stdlib_dirs()
    found: Origin | None = None
    for frame_summary in traceback.extract_tb(tb):
        path = os.path.abspath(frame_summary.filename)
        in_stdlib = path.startswith(stdlib) and "-packages" + os.sep not in path
        if _is_ours(path) or in_stdlib or frame_summary.filename.startswith("<"):
            continue
        found = Origin(frame_summary.filename, frame_summary.lineno or 0)
    return found
