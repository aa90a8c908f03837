"""A launch session: one loaded file, its current arguments and plan, and a preview.

The argument form edits values here; `preview` says what would change before anything
restarts, and `apply` hands the new plan to the supervisor.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from ..describe.python.loader import LoadedFile, load_file
from ..errors import LaunchError
from .machines import Placement
from .model import Plan, PlanDiff, diff_plans
from .resolve import default_params_dir, resolve


@dataclass
class Preview:
    """What applying some argument values would do, or why they cannot be applied."""

    arguments: dict[str, str]
    plan: Plan | None
    diff: PlanDiff | None
    error: str | None


class Session:
    def __init__(self, path: str, arguments: Mapping[str, str],
                 params_dir: Path | None = None, placement: Placement | None = None) -> None:
        """`placement` (`--machines`): each plan made here says which machine runs what."""
        self.path = path
        self.placement = placement
        self.params_dir = params_dir or default_params_dir()
        self.loaded: LoadedFile = load_file(path)
        self.arguments = dict(arguments)
        self.plan: Plan = self._resolve(self.arguments)

    def _resolve(self, values: Mapping[str, str]) -> Plan:
        plan = resolve(self.loaded, dict(values), self.params_dir)
        return self.placement.apply(plan) if self.placement is not None else plan

    def preview(self, edits: Mapping[str, str], running: set[str] | None = None) -> Preview:
        values = {**self.arguments, **edits}
        try:
            plan = self._resolve(values)
        except LaunchError as exc:
            return Preview(values, None, None, str(exc))
        return Preview(values, plan, diff_plans(self.plan, plan, running), None)

    def accept(self, preview: Preview) -> Plan:
        """Makes a previewed plan the current one (the supervisor then runs it)."""
        assert preview.plan is not None
        self.arguments = preview.arguments
        self.plan = preview.plan
        return self.plan

    def reload(self) -> None:
        """Reads the launch file again (after the user edited it)."""
        self.loaded = load_file(self.path)
        self.plan = self._resolve(self.arguments)
