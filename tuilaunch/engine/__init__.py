"""The launch engine: load a launch file, resolve it into a Plan, run it. No UI in here."""

from .describe.python.dsl import SimpleLauncher
from .describe.python.loader import LoadedFile, load_file
from .errors import ArgumentError, DslError, LaunchError, Origin, PackageError
from .plan.model import ActionPlan, ArgumentInfo, Plan, ProcessPlan, TreeItem, Trigger
from .plan.resolve import resolve

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
