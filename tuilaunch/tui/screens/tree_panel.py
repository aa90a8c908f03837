"""The group tree: namespaces, conditions, triggers, includes, nodes with live states."""

from __future__ import annotations

import os
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from rich.text import Text
from textual.message import Message
from textual.widgets import Tree
from textual.widgets.tree import TreeNode

from ...engine.plan.components import component_label
from ...engine.plan.model import ActionKind, Plan, PlanDiff, TreeItem
from ...engine.run.vocabulary.reported_names import current_node_name
from .units import short_bytes, usage_text

ALL = "__all__"

# icon and style per state; the word is always shown too, so 16 colours or NO_COLOR suffice
STATE_LOOK = {
    "pending": ("…", "yellow", "waiting"),
    "running": ("●", "green", "running"),
    "exited": ("■", "", "exited"),
    "failed": ("✗", "red", "failed"),
    "respawning": ("↻", "yellow", "respawning"),
    "skipped": ("○", "dim", "skipped"),
    "stopping": ("◌", "yellow", "stopping"),
    "done": ("✓", "green", "done"),
    "cancelled": ("○", "dim", "cancelled"),
    "unknown": ("?", "yellow", "unknown"),  # placed on a machine whose link is lost
}
# the Linux console's font lacks most of those: plain ASCII there
ASCII_ICONS = {"pending": ".", "running": "*", "exited": "#", "failed": "x",
               "respawning": "~", "skipped": "o", "stopping": "-", "done": "+",
               "cancelled": "o", "unknown": "?"}
# an action "running" is waiting for its service or node
ACTION_WORDS = {"running": "working", "pending": "waiting"}
# a lifecycle node's state, shown after its process state
LIFECYCLE_LOOK = {"unconfigured": "yellow", "inactive": "cyan", "active": "bold green",
                  "finalized": "dim"}
# a component's load result
COMPONENT_LOOK = {"waiting": ("…", "yellow"), "loading": ("…", "yellow"),
                  "loaded": ("✓", "green"), "failed": ("✗", "red"),
                  "cancelled": ("○", "dim"), "skipped": ("○", "dim")}


USAGE_WIDTH = 44
"""From this tree width on, process rows show their CPU and memory (`< >` resize the tree);
narrower, the detail line above the tree shows them for the selected row."""


def ascii_terminal() -> bool:
    return os.environ.get("TERM", "") in ("linux", "vt100", "vt102", "vt220", "ansi")


class RowKind(StrEnum):
    """What a tree row stands for (a StrEnum: it still equals its word, which other
    modules may compare with)."""

    PROCESS = "process"
    ALL = "all"
    """The `all nodes` row: every process's output."""
    GROUP = "group"
    """A group (a namespace, an include, a condition...), or the launch: the tree's root."""
    ACTION = "action"
    COMPONENT = "component"
    """A composable node loaded into its container (whose row is the process)."""


@dataclass
class RowData:
    """What a tree row stands for: a process or action id, a group's processes, or all."""

    kind: RowKind
    ref: str | None
    processes: list[str]


class LaunchTree(Tree[RowData]):
    DEFAULT_CSS = """
    LaunchTree { width: 30; min-width: 12; border-right: tall $panel; overflow-x: hidden; }
    """

    def __init__(self, **kwargs: object) -> None:
        super().__init__("launch", data=RowData(RowKind.GROUP, None, []), **kwargs)  # type: ignore
        self.guide_depth = 2  # narrow indents: the names keep the width
        self.ascii = ascii_terminal()
        if self.ascii:
            self.ICON_NODE = "+ "
            self.ICON_NODE_EXPANDED = "- "
            self.LINES = {style: ("  ", "| ", "`-", "|-") for style in self.LINES}
        self.rows: dict[str, TreeNode[RowData]] = {}
        self.plan: Plan | None = None
        self.details: dict[str, str] = {}
        self.action_labels: dict[str, str] = {}
        self.states: dict[str, str] = {}
        self.preview: PlanDiff | None = None
        self.lifecycle: dict[str, str] = {}
        self.component_rows: dict[str, TreeNode[RowData]] = {}
        self.component_labels: dict[str, str] = {}
        # names processes report in their log lines (OutputStore.reported_names)
        self.reported: dict[str, set[str]] = {}
        self.usage: dict[str, dict[str, Any]] = {}
        """CPU, memory, threads per running process, while the server samples them: of the
        processes it shows them for (figures_shown), and whether memory keeps growing."""
        self._wide: bool | None = None
        self.qos_problems: dict[str, list[str]] = {}
        """Per process, the QoS problems (sentences) its node is part of."""

    def show_plan(self, plan: Plan, states: dict[str, str]) -> None:
        self.plan = plan
        self.states = dict(states)
        self.clear()
        self.rows = {}
        self.component_rows = {}
        self.root.set_label(plan.file.rsplit("/", 1)[-1])
        self.root.data = RowData(RowKind.GROUP, None, [p.id for p in plan.enabled_processes()])
        self.root.add_leaf("all nodes", RowData(RowKind.ALL, ALL, []))
        for child in plan.tree.children:
            self._add(self.root, child)
        self.root.expand_all()
        # Tree numbers its lines when it next paints or idles; until then each new row's line
        # is -1, and moving the cursor to it (`a` or `attach --type` right after a relaunch
        # or the first plan) would select nothing. Numbered now (last_line builds them).
        self.last_line  # noqa: B018

    def _add(self, parent: TreeNode[RowData], item: TreeItem) -> list[str]:
        if item.kind == RowKind.PROCESS and item.ref:
            components = self.plan.process(item.ref).components if self.plan else []
            data = RowData(RowKind.PROCESS, item.ref, [item.ref])
            node = parent.add(item.ref, data) if components else parent.add_leaf(item.ref, data)
            self.rows[item.ref] = node
            self.refresh_row(item.ref)
            self._add_components(node, components if item.enabled else [])
            return [item.ref]
        if item.kind == RowKind.ACTION and item.ref:
            action = next((a for a in self.plan.actions if a.id == item.ref), None) \
                if self.plan else None
            components = list(action.data or []) if action is not None and \
                action.kind == ActionKind.LOAD_COMPONENTS else []
            data = RowData(RowKind.ACTION, item.ref, [])
            node = parent.add(item.label, data) if components else \
                parent.add_leaf(item.label, data)
            self.rows[item.ref] = node
            self.action_labels[item.ref] = item.label
            self.refresh_row(item.ref)
            self._add_components(node, components)
            return []
        node = parent.add(self._group_label(item), RowData(RowKind.GROUP, None, []))
        processes: list[str] = []
        for child in item.children:
            processes += self._add(node, child)
        assert node.data is not None
        node.data.processes = processes
        return processes

    def _add_components(self, parent: TreeNode[RowData], components: list[dict[str, Any]])\
            -> None:
        """A container's (or a LoadComposableNodes action's) components, under its row."""
        for component in components:
            ref = str(component["id"])
            self.component_labels[ref] = component_label(component)
            state = "waiting" if component.get("enabled", True) else "skipped"
            self.component_rows[ref] = parent.add_leaf(
                "", RowData(RowKind.COMPONENT, ref, []))
            self.set_component(ref, state, "")

    def set_component(self, ref: str, state: str, text: str) -> None:
        """A component's load result: unique id, the container's error, or why not sent."""
        node = self.component_rows.get(ref)
        if node is None:
            return
        icon, style = COMPONENT_LOOK.get(state, ("?", ""))
        label = Text()
        label.append(f"{icon} ", style)
        label.append(self.component_labels.get(ref, ref))
        label.append(f" {state}", style or "dim")
        if text and state in ("loaded", "failed", "cancelled"):
            label.append(f" {text}", "dim" if state == "loaded" else style)
        node.set_label(label)

    def set_lifecycle(self, ref: str, state: str) -> None:
        """The live lifecycle state of a lifecycle node's process ('' once it is gone)."""
        if state:
            self.lifecycle[ref] = state
        else:
            self.lifecycle.pop(ref, None)
        self.refresh_row(ref)

    def _group_label(self, item: TreeItem) -> Text:
        label = Text(item.label)
        if item.condition is not None:
            label.append(f" = {item.condition.value}", "bold" if item.enabled else "dim")
        if item.trigger is not None:
            clock = "@" if ascii_terminal() else "⏱"
            label.append(f" {clock} {item.trigger.describe()}", "italic")
        if not item.enabled:
            label.stylize("dim")
        return label

    def set_state(self, ref: str, state: str, detail: str = "") -> None:
        self.states[ref] = state
        if detail:
            self.details[ref] = detail
        self.refresh_row(ref)

    def set_usage(self, usage: dict[str, Any]) -> None:
        """A `resources` event: each running process's CPU and memory (the rows whose text
        changes are repainted); {} clears them (sampling stopped)."""
        old = self.usage
        self.usage = {ref: dict(values) for ref, values in usage.items()
                      if isinstance(values, dict)}
        for ref in set(old) | set(self.usage):
            if old.get(ref) != self.usage.get(ref):
                self.refresh_row(ref)

    def set_qos_problems(self, problems: dict[str, list[str]]) -> None:
        """The QoS problems each process's node is part of; rows that change are repainted."""
        old = self.qos_problems
        self.qos_problems = {ref: list(p) for ref, p in problems.items() if p}
        for ref in set(old) | set(self.qos_problems):
            if old.get(ref) != self.qos_problems.get(ref):
                self.refresh_row(ref)

    class FiguresShown(Message):
        """The CPU and memory column came or went with the tree's width."""

    def on_resize(self) -> None:
        for ref in self.usage:
            self.refresh_row(ref)  # the CPU column comes or goes with the width
        wide = self.size.width >= USAGE_WIDTH
        if wide != self._wide:
            self._wide = wide
            self.post_message(self.FiguresShown())

    def figures_shown(self) -> list[str] | None:
        """The processes whose CPU and memory the Nodes tab shows: every one (None) when
        the tree is wide enough for its column, else the selected row's, on the detail
        line (no process: none)."""
        if self.size.width >= USAGE_WIDTH:
            return None
        node = self.cursor_node
        if node is None or node.data is None or node.data.kind != RowKind.PROCESS:
            return []
        return [node.data.ref] if node.data.ref else []

    def set_preview(self, diff: PlanDiff | None) -> None:
        old = self.preview
        self.preview = diff
        for ref in set(self.rows) & set(_refs(old) | _refs(diff)):
            self.refresh_row(ref)

    def refresh_row(self, ref: str) -> None:
        node = self.rows.get(ref)
        if node is None or self.plan is None:
            return
        state = self.states.get(ref, "pending")
        icon, style, word = STATE_LOOK.get(state, ("?", "", state))
        if self.ascii:
            icon = ASCII_ICONS.get(state, "?")
        if node.data is not None and node.data.kind == RowKind.ACTION:
            word = ACTION_WORDS.get(state, word)
        label = Text()
        if self.preview is not None:
            if ref in self.preview.start:
                label.append("+", "bold green")
            elif ref in self.preview.stop:
                label.append("-", "bold red")
        label.append(f"{icon} ", style)
        usage = self.usage.get(ref) if state == "running" else None
        if usage and usage.get("growing"):
            # first, so that even a narrow tree shows it
            label.append("^mem " if self.ascii else "↑mem ", "bold yellow")
        if self.qos_problems.get(ref) and state == "running":
            label.append("xqos " if self.ascii else "✗qos ", "bold red")
        if node.data is not None and node.data.kind == RowKind.PROCESS:
            proc = self.plan.process(ref)
            label.append(proc.name or ref, "bold" if state == "running" else "")
            label.append(f" [{ref}]" if proc.name else "", "dim")
            if proc.machine:  # placed on another machine (--machines)
                label.append(f" @{proc.machine}", "cyan")
        else:
            label.append(self.action_labels.get(ref, ref))
        detail = self.details.get(ref, "")
        label.append(f" {word}{' ' + detail if detail else ''}", style or "dim")
        lifecycle = self.lifecycle.get(ref)
        if lifecycle:
            label.append(f" · {lifecycle}", LIFECYCLE_LOOK.get(lifecycle, "italic"))
        if usage and usage.get("rss_bytes") is not None and self.size.width >= USAGE_WIDTH:
            cpu = usage.get("cpu_percent")
            cpu_text = f"{cpu:.0f}%" if isinstance(cpu, (int, float)) else "-"
            label.append(f" {cpu_text} {short_bytes(usage.get('rss_bytes'))}", "cyan")
        if node.label != label:  # an unchanged row is not repainted
            node.set_label(label)

    def describe(self, node: TreeNode[RowData]) -> str:
        """The whole story of a row, for the detail line: never cut by the tree's width."""
        data = node.data
        if data is None or self.plan is None:
            return ""
        if data.kind == RowKind.ALL:
            return "all nodes: every process's output, with its id"
        if data.kind == RowKind.GROUP:
            label = node.label.plain if isinstance(node.label, Text) else str(node.label)
            states = [self.states.get(p, "pending") for p in data.processes]
            text = f"{label}: {states.count('running')} of {len(states)} processes running"
            # what the others are doing: while a stop is under way, "0 of 2 running" alone
            # reads as if they had died
            others = [f"{states.count(state)} {STATE_LOOK[state][2]}"
                      for state in ("stopping", "respawning", "failed") if state in states]
            return f"{text}, {', '.join(others)}" if others else text
        ref = data.ref or ""
        state = self.states.get(ref, "pending")
        word = STATE_LOOK.get(state, ("", "", state))[2]
        if data.kind == RowKind.COMPONENT:
            # a component's row says it all: plugin, name, load result
            return node.label.plain if isinstance(node.label, Text) else str(node.label)
        if data.kind == RowKind.ACTION:
            word = ACTION_WORDS.get(state, word)
            text = f"{self.action_labels.get(ref, ref)} [{ref}]: {word}"
        else:
            proc = self.plan.process(ref)
            name = current_node_name(proc.full_name, self.reported.get(ref, ())) or proc.label
            text = f"{ref} ({name}): {word}"
            if self.lifecycle.get(ref):
                text += f", lifecycle state {self.lifecycle[ref]}"
        detail = self.details.get(ref, "")
        usage = self.usage.get(ref) if state == "running" else None
        if usage:
            detail += f" · {usage_text(usage)}"
        problems = self.qos_problems.get(ref) if state == "running" else None
        if problems:
            more = f" (+{len(problems) - 1} more, Topics tab)" if len(problems) > 1 else ""
            detail += f" · QoS: {problems[0]}{more}"
        machine = self.plan.process(ref).machine if data.kind == RowKind.PROCESS else None
        if machine and state == "failed":
            # it may be its machine that failed: r (or t) tries that machine again
            detail += f" · r: try {machine} again"
        return f"{text} {detail}".rstrip()


def _refs(diff: PlanDiff | None) -> set[str]:
    return set() if diff is None else set(diff.start) | set(diff.stop)
