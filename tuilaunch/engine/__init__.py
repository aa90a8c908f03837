"""The launch engine: load a launch file, resolve it into a Plan, run it. No UI in here."""

from .dsl import SimpleLauncher
from .errors import ArgumentError, DslError, LaunchError, Origin, PackageError
from .loader import LoadedFile, load_file
from .plan import ActionPlan, ArgumentInfo, Plan, ProcessPlan, TreeItem, Trigger
from .resolve import resolve

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
