"""Load a launch file: run it with our `launch`, `launch_ros` and `simple_launch` in place.

User files import the real launch API by name; while one is executed here, those names
resolve to the engine's own modules (see `compat`), whatever else is on sys.path.
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any

from ...errors import (
    DslError,
    LaunchError,
    Origin,
    PackageError,
    origin_from_traceback,
    origin_outside_tuilaunch,
)
from ..entities import LaunchDescription, entity_list
from ..environ import Overlay, captured_environ

_lock = threading.RLock()
_loaded_files: set[str] = set()
_command: list[str] = ["ros2", "launch"]
_arguments: dict[str, str] = {}
_ROOTS = ("launch", "launch_ros", "simple_launch", "launch_xml", "launch_yaml")


def set_command_line(positional: list[str] | None = None,
                     arguments: dict[str, str] | None = None) -> None:
    """What `sys.argv` shows while a file loads: `ros2 launch PKG FILE name:=value ...`.

    nav2's ParseMultiRobotPose reads `sys.argv[4:]`, so files see the command line that
    ros2 launch would have been given for the same launch."""
    global _command, _arguments
    if positional is not None:
        _command = ["ros2", "launch", *positional]
    if arguments is not None:
        _arguments = dict(arguments)


def _argv() -> list[str]:
    return [*_command, *(f"{k}:={v}" for k, v in _arguments.items())]


@dataclass
class LoadedFile:
    """A launch file's Description: its top-level entities, lazy until resolved, and what
    its module code and generate_launch_description() wrote into os.environ (kept for what
    follows, as launch keeps it; os.environ itself is put back)."""

    path: str
    entities: list[Any]
    environ: Overlay = field(default_factory=dict)


def known_launch_files() -> set[str]:
    return set(_loaded_files)


@contextmanager
def compat_modules() -> Iterator[None]:
    """Our modules under the launch API's names, restored afterwards."""
    from .compat import build_modules

    with _lock:
        modules = build_modules()
        # a real launch install's submodules must not mix with ours
        shadowed = [name for name in sys.modules
                    if name.split(".")[0] in _ROOTS and name not in modules]
        saved = {name: sys.modules.get(name) for name in [*modules, *shadowed]}
        for name in shadowed:
            del sys.modules[name]
        sys.modules.update(modules)
        saved_argv = sys.argv
        sys.argv = _argv()
        try:
            yield
        finally:
            sys.argv = saved_argv
            for name in [n for n in sys.modules if n.split(".")[0] in _ROOTS]:
                if name not in saved:
                    del sys.modules[name]
            for name, previous in saved.items():
                if previous is None:
                    sys.modules.pop(name, None)
                else:
                    sys.modules[name] = previous


def unsupported_import(exc: BaseException) -> str | None:
    """"tuilaunch does not support launch_ros.X yet" for a name or module of the tree."""
    import re

    from .compat import unsupported_message

    text = str(exc)
    if isinstance(exc, ModuleNotFoundError) and exc.name and exc.name.split(".")[0] in _ROOTS:
        return unsupported_message(exc.name)
    match = re.match(r"cannot import name '(\w+)' from '([\w.]+)'", text)
    if match and match.group(2).split(".")[0] in _ROOTS:
        return unsupported_message(f"{match.group(2)}.{match.group(1)}")
    if text.startswith("tuilaunch does not support"):
        return text
    return None


def load_file(path: str, origin: Origin | None = None) -> LoadedFile:
    """Read an XML or YAML launch file, or execute a Python one and call its
    generate_launch_description() (any other extension is taken as Python, as launch does)."""
    path = os.path.abspath(path)
    if not os.path.isfile(path):
        raise PackageError(f"launch file {path} does not exist", origin)
    _loaded_files.add(path)
    from ..frontends import frontend_of, load_frontend_file

    kind = frontend_of(path)
    if kind is not None:
        return LoadedFile(path, load_frontend_file(path, kind, origin))
    try:
        with open(path, encoding="utf-8") as handle:
            source = handle.read()
        code = compile(source, path, "exec", dont_inherit=True)
    except SyntaxError as exc:
        raise LaunchError(f"syntax error: {exc.msg}", Origin(path, exc.lineno or 0)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise LaunchError(f"cannot read {path}: {exc}", origin) from None
    module = ModuleType(os.path.splitext(os.path.basename(path))[0].replace(".", "_"))
    module.__file__ = path
    try:
        with compat_modules(), captured_environ() as environ:
            exec(code, module.__dict__)
            generate = module.__dict__.get("generate_launch_description")
            if not callable(generate):
                raise LaunchError(f"{path} defines no generate_launch_description()",
                                  Origin(path, 1),
                                  hint="a launch file must define generate_launch_description() "
                                  "or assign sl.launch_description(opaque_function=...) to it")
            description = generate()
    except (LaunchError, BrokenPipeError):  # a closed stdout is the reader's choice
        raise
    except SystemExit as exc:  # sys.exit() in the file: say so instead of ending quietly
        where = origin_from_traceback(sys.exc_info()[2], {path}) or Origin(path, 1)
        raise LaunchError(f"the file called sys.exit({exc.code!r}) while loading",
                          where) from None
    except Exception as exc:  # the user's code raised: point at their line
        tb = sys.exc_info()[2]
        where = origin_from_traceback(tb, {path}) or Origin(path, 0)
        missing = unsupported_import(exc) if isinstance(exc, ImportError | AttributeError) \
            else None
        if missing is not None:
            raise DslError(missing, where) from None
        inner = origin_outside_tuilaunch(tb)
        if inner is not None and inner != where:
            # the error is inside an extension (nav2_common, ...): name its line too
            raise LaunchError(f"{type(exc).__name__}: {exc} (in {inner})", where) from None
        if isinstance(exc, ImportError):
            raise DslError(f"{type(exc).__name__}: {exc}", where,
                           hint="tuilaunch provides launch, launch_ros and simple_launch; "
                           "other modules must be installed in this environment") from None
        raise LaunchError(f"{type(exc).__name__}: {exc}", where) from None
    if description is None:
        line = getattr(getattr(generate, "__code__", None), "co_firstlineno", 1)
        raise LaunchError("generate_launch_description() returned None", Origin(path, line),
                          hint="return sl.launch_description() or a LaunchDescription")
    if isinstance(description, LaunchDescription):
        return LoadedFile(path, list(description.entities), environ)
    return LoadedFile(path, entity_list(description), environ)
