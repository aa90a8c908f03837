"""A Plan back from its JSON (`Plan.to_json`): what a client on another machine is sent of
the plan its session runs, to draw the tree, the argument form and the details.

What `to_json` leaves out (generated parameter files, timeouts, the entities a plan was made
from) is only the runner's business; it gets neutral values here, and such a plan is never
run."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from ..describe.conditions import ConditionOutcome
from ..describe.entities import TriggerOn
from ..errors import Origin
from .model import ActionKind, ActionPlan, ArgumentInfo, Plan, ProcessPlan, TreeItem, Trigger

_ORIGIN = re.compile(r"^(?P<file>.*?):(?P<line>\d+)(?::(?P<column>\d+))?$")


def plan_from_json(data: dict[str, Any]) -> Plan:
    """The Plan `Plan.to_json` described."""
    return Plan(
        file=str(data["file"]),
        arguments=[_argument(a) for a in data.get("arguments") or []],
        processes=[_process(p) for p in data.get("processes") or []],
        actions=[_action(a) for a in data.get("actions") or []],
        tree=_tree(data["tree"]),
        params_dir=Path(),
        warnings=list(data.get("warnings") or []),
    )


def _trigger(data: dict[str, Any] | None) -> Trigger | None:
    if data is None:
        return None
    return Trigger(on=TriggerOn(data["on"]), target=data.get("target"),
                   delay=float(data.get("delay") or 0), io=data.get("io"),
                   after=_trigger(data.get("after")))


def _condition(data: dict[str, Any] | None) -> ConditionOutcome | None:
    if data is None:
        return None
    return ConditionOutcome(str(data["expression"]), str(data["value"]), bool(data["holds"]))


def _origin(text: str | None) -> Origin | None:
    match = _ORIGIN.match(text or "")
    if match is None:
        return None
    column = match["column"]
    return Origin(match["file"], int(match["line"]), None if column is None else int(column))


def _argument(data: dict[str, Any]) -> ArgumentInfo:
    return ArgumentInfo(name=data["name"], default=data.get("default"), value=data.get("value"),
                        description=data.get("description"), choices=data.get("choices"),
                        type=data.get("type") or "string", file=data.get("file") or "",
                        line=data.get("line"), elsewhere=list(data.get("elsewhere") or []))


def _process(data: dict[str, Any]) -> ProcessPlan:
    return ProcessPlan(
        id=data["id"], kind=data["kind"], name=data.get("name"),
        namespace=data.get("namespace") or "/", package=data.get("package"),
        executable=data.get("executable") or "", cmd=list(data.get("cmd") or []),
        parameters=dict(data.get("parameters") or {}),
        parameter_files=list(data.get("parameter_files") or []),
        generated_parameter_files=[], remappings=list(data.get("remappings") or []),
        env=dict(data.get("env") or {}), clear_env=False, cwd=None,
        respawn=bool(data.get("respawn")), respawn_delay=float(data.get("respawn_delay") or 0),
        respawn_max_retries=-1, sigterm_timeout=None, sigkill_timeout=None,
        enabled=bool(data.get("enabled", True)), skipped_by=_condition(data.get("skipped_by")),
        trigger=_trigger(data.get("trigger")), origin=_origin(data.get("origin")),
        error=data.get("error"), components=list(data.get("components") or []),
        lifecycle=bool(data.get("lifecycle")), autostart=bool(data.get("autostart")),
        machine=data.get("machine"), unset_env=list(data.get("unset_env") or []))


def _action(data: dict[str, Any]) -> ActionPlan:
    return ActionPlan(
        id=data["id"], kind=ActionKind(data["kind"]), target=data.get("target"),
        data=data.get("data"),
        namespace=data.get("namespace") or "/", verbosity=data.get("verbosity") or "",
        enabled=bool(data.get("enabled", True)), skipped_by=_condition(data.get("skipped_by")),
        trigger=_trigger(data.get("trigger")), origin=_origin(data.get("origin")))


def _tree(data: dict[str, Any]) -> TreeItem:
    return TreeItem(kind=data["kind"], label=data["label"], enabled=bool(data["enabled"]),
                    namespace=data.get("namespace") or "/",
                    condition=_condition(data.get("condition")),
                    trigger=_trigger(data.get("trigger")), ref=data.get("ref"),
                    children=[_tree(child) for child in data.get("children") or []])
