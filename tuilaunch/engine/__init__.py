"""The launch engine: load a launch file, resolve it into a Plan, run it. No UI in here.

The names below are loaded on first use (PEP 562), so importing one small module of the
engine (packages, session_dir: what shell completion reads) does not load the whole
launch-file frontend."""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .describe.python.dsl import SimpleLauncher
    from .describe.python.loader import LoadedFile, load_file
    from .errors import ArgumentError, DslError, LaunchError, Origin, PackageError
    from .plan.model import ActionPlan, ArgumentInfo, Plan, ProcessPlan, TreeItem, Trigger
    from .plan.resolve import resolve

_WHERE = {
    "SimpleLauncher": ".describe.python.dsl",
    "LoadedFile": ".describe.python.loader",
    "load_file": ".describe.python.loader",
    "ArgumentError": ".errors",
    "DslError": ".errors",
    "LaunchError": ".errors",
    "Origin": ".errors",
    "PackageError": ".errors",
    "ActionPlan": ".plan.model",
    "ArgumentInfo": ".plan.model",
    "Plan": ".plan.model",
    "ProcessPlan": ".plan.model",
    "TreeItem": ".plan.model",
    "Trigger": ".plan.model",
    "resolve": ".plan.resolve",
}


def __getattr__(name: str) -> Any:
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(where, __name__), name)
    globals()[name] = value
    return value


__all__ = [
    "ActionPlan",
    "ArgumentError",
    "ArgumentInfo",
    "DslError",
    "LaunchError",
    "LoadedFile",
    "Origin",
    "PackageError",
    "Plan",
    "ProcessPlan",
    "SimpleLauncher",
    "TreeItem",
    "Trigger",
    "load_file",
    "resolve",
]
