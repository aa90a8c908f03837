"""The Textual app: lays out the panels and forwards between them and the engine.

Engine events reach the UI through one EventBuffer drained on a timer, so a flood from a
node costs one batched write per pane per tick. The App constructor does no I/O: the
supervisor and the ROS bridge start in on_mount.
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import threading
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from rich.text import Text
from textual import on, work
from textual.app import App, ComposeResult, SystemCommand
from textual.binding import Binding
from textual.screen import Screen
from textual.widgets import Footer, Static, TabbedContent, TabPane, Tree

from .engine.plan.session import Preview, Session
from .engine.ros.bridge import RosBridge
from .engine.ros.lifecycle import available_transitions
from .engine.run.engine_thread import EngineThread
from .engine.run.event_buffer import EventBuffer
from .engine.run.supervisor import Event, Supervisor
from .output_store import Line, OutputStore
from .screens.args_panel import ArgsPanel
from .screens.dialogs import HelpScreen, QuitScreen
from .screens.output_panel import NodesView, OutputPanel
from .screens.params_panel import ParamsPanel
from .screens.services_panel import ServicesPanel
from .screens.tree_panel import LaunchTree, RowData

DRAIN_HZ = 20


class TuiLaunchApp(App[int]):
    CSS_PATH = "screens/app.tcss"
    TITLE = "tuilaunch"

    BINDINGS = [
        Binding("1", "tab('nodes')", "Nodes", tooltip="The group tree and node output"),
        Binding("2", "tab('args')", "Args", tooltip="Edit launch arguments"),
        Binding("3", "tab('services')", "Services", tooltip="Call a service"),
        Binding("4", "tab('params')", "Params", tooltip="Get and set parameters"),
        Binding("s", "stop", "Stop", tooltip="Stop the selected node or group"),
        Binding("r", "restart", "Restart", tooltip="Restart the selected node or group"),
        Binding("t", "start", "Start", tooltip="Start the selected node or group"),
        Binding("a", "all_output", "All", show=False, tooltip="Output of all nodes"),
        Binding("right_square_bracket", "lifecycle('up')", "Lifecycle up",
                tooltip="Configure an unconfigured, activate an inactive lifecycle node"),
        Binding("left_square_bracket", "lifecycle('down')", "Lifecycle down",
                tooltip="Deactivate an active, clean up an inactive lifecycle node"),
        Binding("f5", "apply", "Apply", tooltip="Relaunch with the edited arguments"),
        Binding("question_mark", "help", "Help"),
        Binding("q", "request_quit", "Quit"),
        Binding("ctrl+c", "request_quit", "Quit", show=False, priority=True),
    ]

    def __init__(self, session: Session, log_dir: Path, scrollback: int = 5000,
                 sigterm_timeout: float = 5.0, sigkill_timeout: float = 5.0) -> None:
        no_color = os.environ.get("NO_COLOR")
        super().__init__()
        if no_color is not None:
            # Textual takes NO_COLOR out of the environment; the nodes should still see it
            os.environ["NO_COLOR"] = no_color
        self.session = session
        self.log_dir = log_dir
        self.scrollback = scrollback
        self.sigterm_timeout = sigterm_timeout
        self.sigkill_timeout = sigkill_timeout
        self.store = OutputStore(scrollback=scrollback, all_scrollback=scrollback * 4)
        # lines shown per drain tick at most: 20 ticks/s x 2500 is more than anyone reads;
        # the rest is counted on screen and kept in the log files
        self.buffer = EventBuffer(max_lines=2500)
        self.supervisor: Supervisor | None = None
        self.preview: Preview | None = None
        self.exit_status = 0
        self.quitting = False
        self.terminal_lost = False
        self._bridge: RosBridge | None = None
        self._bridge_lock = threading.Lock()

    # --- layout ----------------------------------------------------------------------

    def compose(self) -> ComposeResult:
        yield Static("", id="status")
        with TabbedContent(initial="nodes"):
            with TabPane("1 Nodes", id="nodes"), NodesView(id="nodes-split"):
                yield LaunchTree(id="tree")
                yield OutputPanel(self.store, self.log_dir, max_lines=self.scrollback,
                                  id="output")
            with TabPane("2 Args", id="args"):
                yield ArgsPanel(self.session.plan.arguments, self.session.plan.file,
                                id="args-panel")
            with TabPane("3 Services", id="services"):
                yield ServicesPanel(self.bridge, id="services-panel")
            with TabPane("4 Params", id="params"):
                yield ParamsPanel(self.bridge, lambda: self.session.plan, id="params-panel")
        yield Footer()

    def bridge(self) -> RosBridge:
        """The one rclpy context, shared by the supervisor's actions and the panels."""
        with self._bridge_lock:  # the engine thread and the UI may both ask first
            if self._bridge is None:
                self._bridge = RosBridge()
            return self._bridge

    def on_mount(self) -> None:
        # held, not queried: App.query_one searches the active screen, which is a modal
        # (help, quit) while the engine keeps reporting
        self.launch_tree = self.query_one(LaunchTree)
        self.output_panel = self.query_one(OutputPanel)
        self.args_panel = self.query_one(ArgsPanel)
        self.tabs = self.query_one(TabbedContent)
        self.status_bar = self.query_one("#status", Static)
        # the engine thread reads floods; a shorter GIL slice lets keypresses through sooner
        sys.setswitchinterval(0.001)
        self.engine = EngineThread()
        # built on the engine thread, whose loop its asyncio objects belong to
        self.supervisor = self.engine.call(lambda: Supervisor(
            self.session.plan, self.log_dir, sigterm_timeout=self.sigterm_timeout,
            sigkill_timeout=self.sigkill_timeout, bridge_factory=self.bridge))
        assert self.supervisor is not None
        self.supervisor.subscribe(self.buffer)
        tree = self.launch_tree
        tree.show_plan(self.session.plan, self.supervisor.states)
        self._describe_waiting()
        self.run_supervisor()
        self._drain_timer = self.set_interval(1 / DRAIN_HZ, self.drain)
        loop = asyncio.get_running_loop()
        loop.add_signal_handler(signal.SIGTERM, self.stop_all_and_exit)
        loop.add_signal_handler(signal.SIGHUP, self._terminal_hung_up)
        self.update_status()
        tree.focus()

    @work(group="supervisor", exit_on_error=False)
    async def run_supervisor(self) -> None:
        assert self.supervisor is not None
        self.exit_status = await self.engine.run(self.supervisor.run(keep_alive=True))
        if self._bridge is not None:
            await asyncio.to_thread(self._bridge.close)
            self._bridge = None
        self.drain()  # the last states and lines, then no more ticks during teardown
        self._drain_timer.stop()
        if self.terminal_lost:
            # Textual's teardown writes to the terminal and blocks forever on a hung-up one;
            # every process is stopped and every log closed, so leave now
            os._exit(self.exit_status)
        self.exit(self.exit_status)

    def on_unmount(self) -> None:
        # any exit path that skipped the graceful shutdown still leaves no process behind
        if self.supervisor is not None:
            self.supervisor.kill_all()
            self.engine.stop()
        if self._bridge is not None:
            self._bridge.close()
            self._bridge = None

    # --- engine events -------------------------------------------------------------------

    def drain(self) -> None:
        events = self.buffer.drain()
        if not events:
            self.output_panel.update_status()
            return
        tree = self.launch_tree
        panel = self.output_panel
        fresh: list[Line] = []
        for event in events:
            if event.kind == "output" and event.process:
                fresh += self.store.add(event.process, event.stream or "stdout", event.lines)
            elif event.kind == "log":
                if event.process and self.supervisor is not None:
                    tree.set_state(event.process, self.supervisor.states.get(event.process, ""))
                fresh += self.store.add("launch", "stdout",
                                        [f"[{event.level}] [{event.process or 'launch'}] "
                                         f"{event.reason}"])
            elif event.kind == "lifecycle" and event.process:
                tree.set_lifecycle(event.process, event.reason or "")
                self.refresh_bindings()
            elif event.kind == "component" and event.data:
                data = event.data
                short = f"id {data['unique_id']}" if "unique_id" in data else \
                    str(data.get("error") or data.get("text") or "")
                tree.set_component(str(data["component"]), str(data["state"]), short)
                if data["state"] not in ("loading", "waiting"):
                    fresh += self.store.add("launch", "stdout", [
                        f"[{event.level}] [{event.process}] {event.reason}"])
            elif event.kind == "dropped" and event.process:
                fresh += self.store.add(event.process, "stderr", [
                    f"[WARN] tuilaunch: {event.reason}"])
            elif event.process and self.supervisor is not None:
                state = self.supervisor.states.get(event.process, event.kind)
                tree.set_state(event.process, state, _detail(event))
        if fresh:
            panel.append(fresh)
        panel.update_status()
        self.update_status()

    def update_status(self) -> None:
        if self.supervisor is None:
            return
        counts: dict[str, int] = {}
        for proc in self.session.plan.processes:
            state = self.supervisor.states.get(proc.id, "pending")
            counts[state] = counts.get(state, 0) + 1
        order = ("running", "pending", "exited", "failed", "respawning", "skipped")
        text = "  ".join(f"{counts[s]} {'waiting' if s == 'pending' else s}" for s in order
                         if counts.get(s))
        args = " ".join(f"{k}:={v}" for k, v in self.session.arguments.items())
        prefix = ""
        if self.quitting:
            still = self.running()
            prefix = f"stopping {', '.join(still)}... " if still else "stopped. "
        name = Path(self.session.plan.file).name
        self.status_bar.update(Text(f"{prefix}{name}  {text}  {args}"))

    def _describe_waiting(self) -> None:
        tree = self.launch_tree
        for proc in self.session.plan.processes:
            if proc.enabled and proc.trigger is not None:
                tree.details[proc.id] = f"({proc.trigger.describe()})"
            elif not proc.enabled and proc.skipped_by is not None:
                tree.details[proc.id] = f"({proc.skipped_by.expression} = " \
                                        f"{proc.skipped_by.value!r})"
            elif proc.error:
                tree.details[proc.id] = f"({proc.error})"
            tree.refresh_row(proc.id)

    # --- tree selection and commands -------------------------------------------------------

    @on(Tree.NodeHighlighted, "#tree")
    def _highlighted(self, event: Tree.NodeHighlighted[RowData]) -> None:
        data = event.node.data
        if data is None:
            return
        self.refresh_bindings()  # the lifecycle keys apply to lifecycle nodes only
        if data.kind == "all":
            self.output_panel.show_view(None)
        elif data.kind == "process":
            self.output_panel.show_view(data.ref)

    def selected(self) -> list[str]:
        node = self.launch_tree.cursor_node
        if node is None or node.data is None:
            return []
        if node.data.kind == "all":
            return [p.id for p in self.session.plan.enabled_processes()]
        return list(node.data.processes)

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action in ("stop", "restart", "start", "all_output"):
            if self.supervisor is None or self.tabs.active != "nodes":
                return False
            if action == "all_output":
                return True
            states = [self.supervisor.states.get(p) for p in self.selected()]
            if action == "stop":
                return True if "running" in states else None
            if action == "start":
                return True if any(s not in ("running", "skipped") for s in states) else None
            return True if states else None
        if action == "lifecycle":
            if self.supervisor is None or self.tabs.active != "nodes":
                return False
            selected = self.selected()
            # shown only while a lifecycle node is selected: other launches keep their footer
            if len(selected) != 1 or selected[0] not in self.supervisor.lifecycle.states:
                return False
            return True if self._lifecycle_step(str(parameters[0])) else None
        if action == "apply":
            return True if self.preview is not None and self.preview.plan is not None and \
                self.preview.diff is not None and not self.preview.diff.empty else None
        return True

    def _command(self, verb: str) -> None:
        assert self.supervisor is not None
        supervisor = self.supervisor
        tree = self.launch_tree
        for process in self.selected():
            if verb in ("stop", "restart") and supervisor.states.get(process) == "running":
                tree.set_state(process, "stopping")
            coroutine = getattr(supervisor, verb)(process)
            self.run_worker(self.engine.run(coroutine), group="commands", exit_on_error=False)
        self.refresh_bindings()

    def action_stop(self) -> None:
        self._command("stop")

    def action_restart(self) -> None:
        self._command("restart")

    def action_start(self) -> None:
        self._command("start")

    def _lifecycle_step(self, direction: str) -> tuple[str, str] | None:
        """(process, transition) that `]` (up) or `[` (down) asks of the selected node."""
        selected = self.selected()
        if self.supervisor is None or len(selected) != 1:
            return None
        state = self.supervisor.lifecycle.states.get(selected[0])
        steps = {"up": {"unconfigured": "configure", "inactive": "activate"},
                 "down": {"active": "deactivate", "inactive": "cleanup"}}[direction]
        transition = steps.get(state or "")
        return (selected[0], transition) if transition else None

    def action_lifecycle(self, direction: str) -> None:
        step = self._lifecycle_step(direction)
        if step is not None:
            self.lifecycle_transition(*step)

    def lifecycle_transition(self, process: str, transition: str) -> None:
        """Asks a lifecycle node for a transition; the result arrives as events."""
        assert self.supervisor is not None
        coroutine = self.supervisor.lifecycle.request(process, transition)
        self.run_worker(self.engine.run(coroutine), group="commands", exit_on_error=False)

    def action_all_output(self) -> None:
        tree = self.launch_tree
        tree.move_cursor(tree.root.children[0])
        self.output_panel.show_view(None)

    def action_tab(self, tab: str) -> None:
        self.tabs.active = tab
        self.refresh_bindings()

    @on(TabbedContent.TabActivated)
    def _tab_changed(self, event: TabbedContent.TabActivated) -> None:
        self.refresh_bindings()
        pane = event.pane.id
        # keyboard first: each tab puts the cursor where work starts
        if pane == "nodes":
            self.launch_tree.focus()
        elif pane == "args":
            editors = self.args_panel.query(".arg-editor")
            if editors:
                editors.first().focus()
        elif pane == "services":
            self.query_one(ServicesPanel).refresh_services()
            self.query_one("#svc-filter").focus()
        elif pane == "params":
            self.query_one(ParamsPanel).refresh_nodes()
            self.query_one("#prm-filter").focus()

    def action_help(self) -> None:
        self.push_screen(HelpScreen())

    # --- arguments ---------------------------------------------------------------------------

    @on(ArgsPanel.Edited)
    def _args_edited(self, event: ArgsPanel.Edited) -> None:
        current = {a.name: a.value for a in self.session.plan.arguments}
        edits = {k: v for k, v in event.values.items() if v != current.get(k)}
        panel = self.args_panel
        tree = self.launch_tree
        if not edits:
            self.preview = None
            tree.set_preview(None)
            panel.set_preview_text("No change from what runs now.", error=False)
            self.refresh_bindings()
            return
        running = {p for p, s in (self.supervisor.states.items() if self.supervisor else ())
                   if s == "running"}
        self.preview = self.session.preview(edits, running)
        if self.preview.error is not None or self.preview.diff is None:
            tree.set_preview(None)
            panel.set_preview_text(f"Cannot apply: {self.preview.error}", error=True)
        else:
            tree.set_preview(self.preview.diff)
            panel.set_preview_text(_describe_diff(self.preview), error=False)
        self.refresh_bindings()

    @on(ArgsPanel.ApplyRequested)
    def _apply_requested(self) -> None:
        self.action_apply()

    def action_apply(self) -> None:
        preview = self.preview
        if preview is None or preview.plan is None or preview.diff is None:
            self.notify("nothing to apply" if preview is None else
                        f"cannot apply: {preview.error}", severity="warning")
            return
        self.relaunch(preview)

    @work(group="relaunch", exclusive=True, exit_on_error=False)
    async def relaunch(self, preview: Preview) -> None:
        assert self.supervisor is not None
        plan = self.session.accept(preview)
        diff = await self.engine.run(self.supervisor.replace_plan(plan))
        self.preview = None
        tree = self.launch_tree
        tree.set_preview(None)
        tree.show_plan(plan, self.supervisor.states)
        self._describe_waiting()
        self.args_panel.set_preview_text(
            f"Applied. Stopped: {', '.join(diff.stop) or 'none'}; started: "
            f"{', '.join(diff.start) or 'none'}.", error=False)
        self.update_status()
        self.refresh_bindings()

    # --- quitting ----------------------------------------------------------------------------

    def running(self) -> list[str]:
        if self.supervisor is None:
            return []
        return [p for p, s in self.supervisor.states.items() if s == "running"]

    def action_request_quit(self) -> None:
        running = self.running()
        if not running:
            self.stop_all_and_exit()
            return

        def answered(stop: bool | None) -> None:
            if stop:
                self.stop_all_and_exit()

        self.push_screen(QuitScreen(running), answered)

    async def action_quit(self) -> None:
        self.action_request_quit()

    def _terminal_hung_up(self) -> None:
        """SIGHUP: the ssh session or tmux pane is gone; stop everything, then leave."""
        self.terminal_lost = True
        self.stop_all_and_exit()

    def stop_all_and_exit(self) -> None:
        """Shutdown escalation runs; the supervisor worker exits the app when all are gone."""
        if self.supervisor is None:
            self.exit(0)
            return
        self.quitting = True
        for process in self.running():
            self.launch_tree.set_state(process, "stopping")
        self.update_status()
        self.run_worker(self.engine.run(self.supervisor.shutdown("quit from the UI")),
                        group="shutdown", exit_on_error=False)

    # --- command palette ---------------------------------------------------------------------

    def get_system_commands(self, screen: Screen[Any]) -> Iterable[SystemCommand]:
        yield from super().get_system_commands(screen)
        yield SystemCommand("Stop selected", "Stop the selected node or group", self.action_stop)
        yield SystemCommand("Restart selected", "Restart the selected node or group",
                            self.action_restart)
        yield SystemCommand("Start selected", "Start the selected node or group",
                            self.action_start)
        yield SystemCommand("Apply arguments", "Relaunch with the edited arguments",
                            self.action_apply)
        selected = self.selected() if self.supervisor is not None else []
        if len(selected) == 1 and self.supervisor is not None:
            process = selected[0]
            state = self.supervisor.lifecycle.states.get(process)
            for transition in available_transitions(state):
                yield SystemCommand(
                    f"Lifecycle: {transition.replace('_', ' ')} {process}",
                    f"Ask the lifecycle node (now {state}) for this transition",
                    lambda t=transition, p=process: self.lifecycle_transition(p, t))
        for tab, title in (("nodes", "Nodes"), ("args", "Arguments"), ("services", "Services"),
                           ("params", "Parameters")):
            yield SystemCommand(f"Open {title}", f"Show the {title} tab",
                                lambda tab=tab: self.action_tab(tab))


def _detail(event: Event) -> str:
    if event.kind == "started":
        return f"pid {event.pid}"
    if event.kind in ("exited", "failed", "respawning"):
        return f"({event.reason})"
    return ""


def _describe_diff(preview: Preview) -> str:
    assert preview.diff is not None and preview.plan is not None
    diff = preview.diff
    if diff.empty:
        return "No process changes; F5 applies the new values anyway."
    stop_only = [p for p in diff.stop if p not in diff.start]
    restart = [p for p in diff.stop if p in diff.start]
    start_only = [p for p in diff.start if p not in diff.stop]
    parts = []
    if start_only:
        parts.append(f"would start: {', '.join(start_only)}")
    if restart:
        parts.append(f"would restart: {', '.join(restart)}")
    if stop_only:
        parts.append(f"would stop: {', '.join(stop_only)}")
    return "; ".join(parts) + ".  F5 applies."


def make_app(path: str, arguments: dict[str, str], log_dir: Path, **options: Any)\
        -> TuiLaunchApp:
    """The one factory for the CLI and the tests, so tests run the real wiring."""
    return TuiLaunchApp(Session(path, arguments), log_dir, **options)
