"""Text renderings of a Plan for `--print` and `--show-args`."""

from __future__ import annotations

import os
from typing import Any

from ..engine.plan.components import component_label
from ..engine.plan.machines import Placement
from ..engine.plan.model import ActionKind, ArgumentInfo, Plan, ProcessPlan, TreeItem

COMMAND_WIDTH = 60
"""An ExecuteProcess's command is cut here in the tree (--print --json has it whole)."""


def format_arguments(arguments: list[ArgumentInfo], top_file: str) -> str:
    # ros2 launch's words and layout (ros2launch's print_arguments_of_launch_description,
    # the description as DeclareLaunchArgument builds it); a required argument, and where
    # an argument of an included file is declared, are tuilaunch's additions
    lines = ["Arguments (pass arguments as '<name>:=<value>'):", ""]
    if not arguments:
        return "\n".join([*lines, "  No arguments.", ""])
    for arg in arguments:
        lines.append(f"    '{arg.name}':")
        lines.append(f"        {argument_description(arg)}")
        if arg.default is None:
            lines.append("        (required)")
        else:
            lines.append(f"        (default: '{arg.default}')")
        if os.path.abspath(arg.file) != os.path.abspath(top_file):
            lines.append(f"        declared in {arg.file}")
        for other in arg.elsewhere:
            lines.append(f"        declared again with {other}")
        lines.append("")
    return "\n".join(lines)


def argument_description(arg: ArgumentInfo) -> str:
    """DeclareLaunchArgument's description: its choices are said in it."""
    if not arg.description:
        return f"One of: {arg.choices}" if arg.choices else "no description given"
    if not arg.choices:
        return arg.description
    text = arg.description if arg.description.endswith(".") else arg.description + "."
    return f"{text} Valid choices are: {arg.choices}"


def process_title(proc: ProcessPlan) -> str:
    """How the tree names a process: a ROS node by its node name (`/r2/talker`, or
    `/r2/<talker>` when its code names it); an ExecuteProcess, which has no node name (as
    ros2 launch describes it: by its cmd), by its command line, `$ sh -c 'sleep 1'`."""
    if proc.kind != "process":
        return proc.label
    import shlex

    line = shlex.join(proc.cmd)
    return "$ " + (line if len(line) <= COMMAND_WIDTH else line[:COMMAND_WIDTH - 1] + "…")


def _annotations(item: TreeItem, plan: Plan) -> str:
    notes = []
    if item.kind == "process" and item.ref:
        proc = plan.process(item.ref)
        notes.append(f"[{proc.id}]")
        if proc.machine:
            notes.append(f"@{proc.machine}")
        if proc.package:
            notes.append(f"({proc.package}/{proc.executable})")
        if proc.lifecycle:
            notes.append("lifecycle, autostart" if proc.autostart else "lifecycle")
        if proc.enabled and proc.error and proc.machine is None:
            notes.append(f"!! {proc.error}")
    if item.condition is not None:
        if item.kind == "group":
            notes.append(f"= {item.condition.value!r}")
        elif not item.enabled:
            notes.append(f"({item.condition.expression} = {item.condition.value!r})")
    if item.trigger is not None and item.kind == "group":
        notes.append(f"<{item.trigger.describe()}>")
    return " ".join(notes)


def _components(item: TreeItem, plan: Plan) -> list[dict[str, Any]]:
    """What a container process or a LoadComposableNodes action will load."""
    if not item.ref or not item.enabled:
        return []
    if item.kind == "process":
        return plan.process(item.ref).components
    action = next((a for a in plan.actions if a.id == item.ref), None)
    if action is not None and action.kind == ActionKind.LOAD_COMPONENTS:
        return list(action.data or [])
    return []


def _component_line(component: dict[str, Any]) -> str:
    text = f"component {component_label(component)}"
    if not component.get("enabled", True):
        return "(skipped) " + text
    if component.get("parameters"):
        text += f"  {len(component['parameters'])} parameter(s)"
    if component.get("error"):
        text += f"  !! {component['error']}"
    return text


def format_tree(plan: Plan) -> str:
    enabled = plan.enabled_processes()
    # a process marked !! cannot start (checked here; one placed elsewhere, there)
    blocked = sum(1 for p in enabled if p.error and p.machine is None)
    header = f"{os.path.basename(plan.file)}: {len(enabled) - blocked} of " \
        f"{len(plan.processes)} processes will run"
    if blocked:
        header += f" ({blocked} cannot start: !!)"
    lines = [header]

    def walk(item: TreeItem, prefix: str) -> None:
        for index, child in enumerate(item.children):
            last = index == len(item.children) - 1
            mark = "" if child.enabled else "(skipped) "
            notes = _annotations(child, plan)
            label = process_title(plan.process(child.ref)) \
                if child.kind == "process" and child.ref else child.label
            lines.append(f"{prefix}{'└─ ' if last else '├─ '}{mark}{label}"
                         + (f"  {notes}" if notes else ""))
            inner = prefix + ("   " if last else "│  ")
            components = _components(child, plan)
            for number, component in enumerate(components):
                end = number == len(components) - 1 and not child.children
                lines.append(f"{inner}{'└─ ' if end else '├─ '}{_component_line(component)}")
            walk(child, inner)

    walk(plan.tree, "")
    skipped = [p for p in plan.processes if not p.enabled and p.skipped_by is not None]
    if skipped:
        lines.append("")
        lines.append("Not running:")
        for proc in skipped:
            assert proc.skipped_by is not None
            lines.append(f"  {proc.id} {process_title(proc)}: {proc.skipped_by.expression} is "
                         f"{proc.skipped_by.value!r}")
    for warning in plan.warnings:
        lines.append(f"warning: {warning}")
    return "\n".join(lines) + "\n"


def format_placement(plan: Plan, placement: Placement) -> str:
    """`--print --machines`: which machine runs what (the rules' warnings are the plan's)."""
    lines = ["", "Placement:"]
    here = [p.id for p in plan.processes if p.enabled and p.machine is None]
    lines.append(f"  here: {', '.join(here) if here else '(nothing)'}")
    for name, machine in placement.machines.machines.items():
        placed = [p.id for p in plan.processes if p.enabled and p.machine == name]
        if placed:
            lines.append(f"  {name} ({machine.host}): {', '.join(placed)}")
    return "\n".join(lines) + "\n"
