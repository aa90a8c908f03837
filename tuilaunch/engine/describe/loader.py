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
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from ..errors import DslError, LaunchError, Origin, PackageError, origin_from_traceback
from .entities import LaunchDescription, entity_list

_lock = threading.RLock()
_loaded_files: set[str] = set()


@dataclass
class LoadedFile:
    """A launch file's Description: its top-level entities, lazy until resolved."""

    path: str
    entities: list[Any]


def known_launch_files() -> set[str]:
    return set(_loaded_files)


@contextmanager
def compat_modules() -> Iterator[None]:
    """Our modules under the launch API's names, restored afterwards."""
    from .compat import build_modules

    with _lock:
        modules = build_modules()
        saved = {name: sys.modules.get(name) for name in modules}
        sys.modules.update(modules)
        try:
            yield
        finally:
            for name, previous in saved.items():
                if previous is None:
                    sys.modules.pop(name, None)
                else:
                    sys.modules[name] = previous


def load_file(path: str, origin: Origin | None = None) -> LoadedFile:
    """Read an XML or YAML launch file, or execute a Python one and call its
    generate_launch_description() (any other extension is taken as Python, as launch does)."""
    path = os.path.abspath(path)
    if not os.path.isfile(path):
        raise PackageError(f"launch file {path} does not exist", origin)
    _loaded_files.add(path)
    from .frontends import frontend_of, load_frontend_file

    kind = frontend_of(path)
    if kind is not None:
        return LoadedFile(path, load_frontend_file(path, kind, origin))
    try:
        with open(path, encoding="utf-8") as handle:
            source = handle.read()
        code = compile(source, path, "exec")
    except SyntaxError as exc:
        raise LaunchError(f"syntax error: {exc.msg}", Origin(path, exc.lineno or 0)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise LaunchError(f"cannot read {path}: {exc}", origin) from None
    module = ModuleType(os.path.splitext(os.path.basename(path))[0].replace(".", "_"))
    module.__file__ = path
    try:
        with compat_modules():
            exec(code, module.__dict__)
            generate = module.__dict__.get("generate_launch_description")
            if not callable(generate):
                raise LaunchError(f"{path} defines no generate_launch_description()",
                                  Origin(path, 1),
                                  hint="a launch file must define generate_launch_description() "
                                  "or assign sl.launch_description(opaque_function=...) to it")
            description = generate()
    except LaunchError:
        raise
    except Exception as exc:  # the user's code raised: point at their line
        where = origin_from_traceback(sys.exc_info()[2], {path}) or Origin(path, 0)
        if isinstance(exc, ImportError):
            raise DslError(f"{type(exc).__name__}: {exc}", where,
                           hint="tuilaunch provides launch, launch_ros and simple_launch; "
                           "other modules must be installed in this environment") from None
        raise LaunchError(f"{type(exc).__name__}: {exc}", where) from None
    if description is None:
        raise LaunchError("generate_launch_description() returned None", Origin(path, 0),
                          hint="return sl.launch_description() or a LaunchDescription")
    if isinstance(description, LaunchDescription):
        return LoadedFile(path, list(description.entities))
    return LoadedFile(path, entity_list(description))
