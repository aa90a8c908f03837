"""A launch session: one loaded file, its current arguments and plan, and a preview.

The argument form edits values here; `preview` says what would change before anything
restarts, and `apply` hands the new plan to the supervisor.

A relaunch reads the launch file again, as a new `ros2 launch` would: an edited file is
what runs after it, and a file that no longer loads is refused with its error while the
launch runs on as it was. A preview reads the file again only when it changed on disk
(its size or modification time), and then also says what the edit alone changes.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..describe.python.loader import LoadedFile, load_file
from ..errors import LaunchError
from .model import Plan, PlanDiff, diff_plans
from .resolve import default_params_dir, resolve

if TYPE_CHECKING:
    from .machines import Placement

Stamp = tuple[int, int] | None
"""A file's modification time (ns) and size; None when it cannot be read."""


def file_stamp(path: str) -> Stamp:
    try:
        info = os.stat(path)
    except OSError:
        return None
    return (info.st_mtime_ns, info.st_size)


@dataclass
class Preview:
    """What applying some argument values would do, or why they cannot be applied."""

    arguments: dict[str, str]
    plan: Plan | None
    diff: PlanDiff | None
    error: str | None
    file_changes: PlanDiff | None = None
    """The launch file (or a file it includes) changed on disk since the running plan was
    made: what the edit alone changes (with the values that run now). None when it did not
    (or, for an included file, when argument edits come with it: their diff says it all)."""
    edited: str | None = None
    """Which file changed, for the operator: `bringup.py`, or `a file bringup.py includes`."""
    loaded: LoadedFile | None = None
    """The file as read for this preview (`accept` keeps it)."""
    stamp: Stamp = None


class Session:
    def __init__(self, path: str, arguments: Mapping[str, str],
                 params_dir: Path | None = None, placement: Placement | None = None) -> None:
        """`placement` (`--machines`): each plan made here says which machine runs what."""
        self.path = path
        self.placement = placement
        self.params_dir = params_dir or default_params_dir()
        self.stamp: Stamp = file_stamp(path)
        self.loaded: LoadedFile = load_file(path)
        self.arguments = dict(arguments)
        self.plan: Plan = self._resolve(self.arguments)
        self._edited: tuple[Stamp, LoadedFile] | None = None  # the file as edited, read once

    def _resolve(self, values: Mapping[str, str], loaded: LoadedFile | None = None) -> Plan:
        plan = resolve(loaded or self.loaded, dict(values), self.params_dir)
        return self.placement.apply(plan) if self.placement is not None else plan

    def read_file(self, always: bool = False) -> tuple[LoadedFile, Stamp]:
        """The launch file as it is on disk: the one the running plan was made from while
        it is unchanged (unless `always`: a relaunch reads it again, as ros2 launch would).
        LaunchError (file:line) when it no longer loads."""
        stamp = file_stamp(self.path)
        if not always and stamp == self.stamp:
            return self.loaded, stamp
        if not always and self._edited is not None and self._edited[0] == stamp:
            return self._edited[1], stamp
        loaded = load_file(self.path)
        self._edited = (stamp, loaded)
        return loaded, stamp

    def preview(self, edits: Mapping[str, str], running: set[str] | None = None,
                reread: bool = False) -> Preview:
        """What these values would do. `reread`: read the file again whatever its stamp says
        (a relaunch about to be applied)."""
        values = {**self.arguments, **edits}
        try:
            loaded, stamp = self.read_file(always=reread)
        except LaunchError as exc:
            return Preview(values, None, None, f"the launch file no longer loads: {exc}")
        try:
            plan = self._resolve(values, loaded)
        except LaunchError as exc:
            return Preview(values, None, None, str(exc), loaded=loaded, stamp=stamp)
        file_changes, edited = None, None
        name = os.path.basename(self.path)
        if stamp != self.stamp:
            edited = name
            try:
                same_values = plan if values == self.arguments else self._resolve(
                    self.arguments, loaded)
                # every changed process counts, running or not: what the file changes
                file_changes = diff_plans(self.plan, same_values)
            except LaunchError:  # the edit needs the new values: the whole diff says it
                file_changes = diff_plans(self.plan, plan)
        elif values == self.arguments:
            # included files are read again at every resolve: with the same values, any
            # change comes from one of them
            changes = diff_plans(self.plan, plan)
            if not changes.empty:
                file_changes, edited = changes, f"a file {name} includes"
        return Preview(values, plan, diff_plans(self.plan, plan, running), None,
                       file_changes=file_changes, edited=edited, loaded=loaded, stamp=stamp)

    def accept(self, preview: Preview) -> Plan:
        """Makes a previewed plan the current one (the supervisor then runs it)."""
        assert preview.plan is not None
        self.arguments = preview.arguments
        self.plan = preview.plan
        if preview.loaded is not None:
            self.loaded, self.stamp = preview.loaded, preview.stamp
        return self.plan

    def undeclared(self) -> list[str]:
        """Values given for arguments the file does not declare (a typo: `robto:=r2`): they
        change nothing, so they are not shown as applied."""
        declared = {a.name for a in self.plan.arguments}
        return [name for name in self.arguments if name not in declared]

    def checkpoint(self) -> dict[str, Any]:
        """The session as it is, for `rollback` (a relaunch the supervisor refused)."""
        return dict(vars(self))

    def rollback(self, saved: dict[str, Any]) -> None:
        vars(self).update(saved)

    def reload(self) -> None:
        """Reads the launch file again (after the user edited it)."""
        self.loaded, self.stamp = load_file(self.path), file_stamp(self.path)
        self.plan = self._resolve(self.arguments)
