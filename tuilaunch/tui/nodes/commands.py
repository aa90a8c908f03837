"""Commands on the Nodes tab's selection: stop, restart, start, the lifecycle steps, and
which of them apply to it.

`SelectionCommands` is an object a session's view (session_view.py) holds over its tree;
the app's keys (`s`, `r`, `t`, `]`, `[`, `a`) and its command palette call it. It reaches
the session through the view (`NodesHost`): its client on the engine thread, the plan, the
stops it asked.
"""

from __future__ import annotations

import asyncio
from typing import Any

from textual.widget import Widget

from ...client.port import Verb
from ...engine.plan.model import ActionKind
from ..output_store import OutputStore
from ..screens.dialogs import ConfirmScreen
from ..screens.tree_panel import LaunchTree, RowKind
from .host import NodesHost
from .lifecycle_steps import LifecycleSteps


class SelectionCommands:
    """The selected row of `tree` and what the keys do to it, run as workers of `owner`
    (the tab): a command outlives no tab."""

    def __init__(self, owner: Widget, host: NodesHost, tree: LaunchTree,
                 store: OutputStore, who: str = "") -> None:
        self.owner, self.host, self.tree, self.store = owner, host, tree, store
        self.who = who
        """The session a question names (a fleet's `nuc:base`; one TUI's needs none)."""
        self.lifecycle_steps = LifecycleSteps()
        """`]`, `[` on lifecycle nodes, in the order typed."""

    def selected(self) -> list[str]:
        """The processes of the selected row: one, a group's, or all of them."""
        node = self.tree.cursor_node
        if node is None or node.data is None:
            return []
        if node.data.kind == RowKind.ALL:
            return [p.id for p in self.host.session.plan.enabled_processes()]
        return list(node.data.processes)

    def applies(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """As Textual's check_action for these keys: False hides the key, None greys it."""
        supervisor = self.host.supervisor
        if supervisor is None:
            return False
        if action == "all_output":
            return True
        if action == "lifecycle":
            selected = self.selected()
            # shown only while a lifecycle node is selected: other launches keep their footer
            if len(selected) != 1 or selected[0] not in supervisor.lifecycle.states:
                return False
            return True if self.lifecycle_step(str(parameters[0])) else None
        states = [supervisor.states.get(p) for p in self.selected()]
        if action == "stop":  # one waiting to respawn can be stopped too: it stays down
            return True if "running" in states or "respawning" in states else None
        if action == "start":
            return True if any(s not in ("running", "skipped") for s in states) else None
        return True if states else None

    def command(self, verb: Verb) -> None:
        """Stop, restart or start the selection; a stop or restart of more than one
        process (the root, all nodes, a group) asks first, from a key as from the palette."""
        supervisor = self.host.supervisor
        assert supervisor is not None
        # what the plan runs: a node its condition skipped (`listener:=false`) is no part
        # of the launch, and a group's start or restart never starts it (the session
        # refuses it too, for every client)
        processes = [p for p in self.selected() if supervisor.states.get(p) != "skipped"]
        if verb == "stop":
            touched = [p for p in processes
                       if supervisor.states.get(p) in ("running", "respawning")]
        else:
            touched = processes
        if verb in ("stop", "restart") and len(touched) > 1:
            def answered(yes: bool | None) -> None:
                if yes:
                    self._run(verb, processes)

            what = "running processes" if verb == "stop" else "processes"
            self.owner.app.push_screen(ConfirmScreen(
                f"{verb.capitalize()} all {len(touched)} {what}"
                f"{f' of {self.who}' if self.who else ''}: {', '.join(touched[:6])}"
                f"{' ...' if len(touched) > 6 else ''}?", f"{verb.capitalize()} them (y)"),
                answered)
            return
        self._run(verb, processes)

    def _run(self, verb: Verb, processes: list[str]) -> None:
        supervisor = self.host.supervisor
        assert supervisor is not None
        commands = []
        for process in processes:
            if verb in ("stop", "restart"):
                self.host.asked_to_stop.add(process)
            commands.append(supervisor.command(verb, process))
        actions = self._actions_to_rerun() if verb in ("restart", "start") else []
        self.owner.run_worker(self._carry_out(commands, actions), group="commands",
                              exit_on_error=False)
        # the rows say "stopping" when the session says so (its Stopping event), as every
        # client attached sees it
        self.owner.app.refresh_bindings()

    async def _carry_out(self, commands: list[Any], actions: list[str]) -> None:
        """The commands together; then the group's actions (set_parameters, call_service)
        again, so a restarted node gets what the launch file gave it after its start."""
        supervisor, engine = self.host.supervisor, self.host.engine
        assert supervisor is not None
        results = await asyncio.gather(*(engine.run(c) for c in commands),
                                       return_exceptions=True)
        for result in results:
            if isinstance(result, Exception):  # e.g. its machine could not be reached
                self.owner.app.notify(str(result).split(": ", 1)[-1] if str(result).startswith(
                    "session ") else str(result), severity="error", timeout=8)
        for action in actions:
            self.owner.run_worker(engine.run(supervisor.run_action(action)),
                                  group="commands", exit_on_error=False)

    def _actions_to_rerun(self) -> list[str]:
        """The enabled one-off actions of the selected group, or for one node those of its
        group that wait for it or address it by name."""
        node = self.tree.cursor_node
        if node is None or node.data is None or node.data.kind == RowKind.ACTION:
            return []
        plan = self.host.session.plan
        enabled = {a.id: a for a in plan.actions if a.enabled and a.kind in (
            ActionKind.SET_PARAMETERS, ActionKind.CALL_SERVICE) and (
                a.trigger is None or a.trigger.on not in ("io", "shutdown"))}
        if node.data.kind in (RowKind.GROUP, RowKind.ALL):
            return [ref for ref in _action_refs(node) if ref in enabled]
        process = node.data.ref
        parent = node.parent
        if process is None or parent is None:
            return []
        proc = plan.process(process)
        names = {proc.full_name} | self.store.reported_names.get(process, set())
        chosen = []
        for ref in _action_refs(parent):
            action = enabled.get(ref)
            if action is None:
                continue
            waits_for = action.trigger is not None and _trigger_targets(action.trigger,
                                                                        process)
            addressed = action.kind == ActionKind.SET_PARAMETERS and str(action.target) in names
            if waits_for or addressed:
                chosen.append(ref)
        return chosen

    # --- lifecycle ------------------------------------------------------------------------

    def lifecycle_step(self, direction: str) -> tuple[str, str] | None:
        """(process, transition) that `]` (up) or `[` (down) asks of the selected node:
        from the state it will be in once the steps asked before are done."""
        selected = self.selected()
        supervisor = self.host.supervisor
        if supervisor is None or len(selected) != 1:
            return None
        transition = self.lifecycle_steps.step(
            selected[0], supervisor.lifecycle.states.get(selected[0]), direction)
        return (selected[0], transition) if transition else None

    def lifecycle(self, direction: str) -> None:
        step = self.lifecycle_step(direction)
        if step is not None:
            self.lifecycle_transition(*step)

    def lifecycle_transition(self, process: str, transition: str) -> None:
        """Asks a lifecycle node for a transition, after those asked before; the result
        arrives as events."""
        supervisor, engine = self.host.supervisor, self.host.engine
        assert supervisor is not None
        self.owner.run_worker(self.lifecycle_steps.take(process, transition, lambda: engine.run(
            supervisor.lifecycle.request(process, transition))), group="commands",
            exit_on_error=False)


def _action_refs(node: Any) -> list[str]:
    """Action ids in a tree row's subtree, in the tree's order."""
    refs = []
    for child in node.children:
        data = child.data
        if data is not None and data.kind == RowKind.ACTION and data.ref:
            refs.append(data.ref)
        refs += _action_refs(child)
    return refs


def _trigger_targets(trigger: Any, process: str) -> bool:
    while trigger is not None:
        if trigger.target == process:
            return True
        trigger = trigger.after
    return False
