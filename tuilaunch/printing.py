"""Text renderings of a Plan for `--print` and `--show-args`."""

from __future__ import annotations

import os

from .engine.plan.model import ArgumentInfo, Plan, TreeItem


def format_arguments(arguments: list[ArgumentInfo], top_file: str) -> str:
    if not arguments:
        return "No arguments.\n"
    lines = ["Arguments (pass arguments as '<name>:=<value>'):", ""]
    for arg in arguments:
        lines.append(f"    '{arg.name}':")
        lines.append(f"        {arg.description or 'no description given'}")
        if arg.choices:
            lines.append(f"        Valid choices are: {arg.choices}")
        if arg.default is None:
            lines.append("        (required)")
        else:
            lines.append(f"        (default: '{arg.default}', type: {arg.type})")
        if os.path.abspath(arg.file) != os.path.abspath(top_file):
            lines.append(f"        declared in {arg.file}")
        lines.append("")
    return "\n".join(lines)


def _annotations(item: TreeItem, plan: Plan) -> str:
    notes = []
    if item.kind == "process" and item.ref:
        proc = plan.process(item.ref)
        notes.append(f"[{proc.id}]")
        if proc.package:
            notes.append(f"({proc.package}/{proc.executable})")
        if proc.enabled and proc.error:
            notes.append(f"!! {proc.error}")
    if item.condition is not None:
        if item.kind == "group":
            notes.append(f"= {item.condition.value!r}")
        elif not item.enabled:
            notes.append(f"({item.condition.expression} = {item.condition.value!r})")
    if item.trigger is not None and item.kind == "group":
        notes.append(f"<{item.trigger.describe()}>")
    return " ".join(notes)


def format_tree(plan: Plan) -> str:
    lines = [f"{os.path.basename(plan.file)}: {len(plan.enabled_processes())} of "
             f"{len(plan.processes)} processes will run"]

    def walk(item: TreeItem, prefix: str) -> None:
        for index, child in enumerate(item.children):
            last = index == len(item.children) - 1
            mark = "" if child.enabled else "(skipped) "
            notes = _annotations(child, plan)
            lines.append(f"{prefix}{'└─ ' if last else '├─ '}{mark}{child.label}"
                         + (f"  {notes}" if notes else ""))
            walk(child, prefix + ("   " if last else "│  "))

    walk(plan.tree, "")
    skipped = [p for p in plan.processes if not p.enabled and p.skipped_by is not None]
    if skipped:
        lines.append("")
        lines.append("Not running:")
        for proc in skipped:
            assert proc.skipped_by is not None
            lines.append(f"  {proc.id} {proc.label}: {proc.skipped_by.expression} is "
                         f"{proc.skipped_by.value!r}")
    for warning in plan.warnings:
        lines.append(f"warning: {warning}")
    return "\n".join(lines) + "\n"
