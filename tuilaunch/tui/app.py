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
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from rich.text import Text
from textual import events, on, work
from textual.app import App, ComposeResult, SystemCommand
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen, Screen
from textual.widget import Widget
from textual.widgets import Button, Footer, OptionList, Static, TabbedContent, TabPane, Tree

from ..client.remote_supervisor import RemoteSupervisor
from ..engine.plan.session import Preview, Session
from ..engine.ros.bridge import RosBridge
from ..engine.ros.lifecycle import available_transitions
from ..engine.run.engine_thread import EngineThread
from ..engine.run.event_buffer import EventBuffer
from ..engine.run.supervisor import Event, Supervisor
from .output_store import ERROR, INFO, WARN, Line, OutputStore
from .screens.args_panel import ArgsPanel, check_plan, check_values
from .screens.dialogs import ConfirmScreen, HelpScreen, QuitScreen
from .screens.fields import Field, after_escape
from .screens.output_panel import NodesView, OutputPanel
from .screens.params_panel import ParamsPanel
from .screens.services_panel import ServicesPanel
from .screens.tree_panel import LaunchTree, RowData

# the UI's tick: events are taken from the engine this often; the output pane repaints at
# most PANE_FPS times a second and only when what it shows changed, so a terminal over ssh
# gets little more than what changed on screen
DRAIN_HZ = 10
PANE_FPS = 1.0


class LaunchTabs(TabbedContent):
    """Tabs that change only when asked (keys 1-4, a click on a tab).

    TabbedContent also switches to whichever pane a widget was focused in, when its
    message arrives: with keys that arrive together (escape, 3) that message is late and
    flips the tab back."""

    def _on_tab_pane_focused(self, event: TabPane.Focused) -> None:
        event.stop()


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
        Binding("d", "detach", "Detach", tooltip="Leave the launch running; tuilaunch attach "
                "opens it again"),
        Binding("question_mark", "help", "Help"),
        Binding("q", "request_quit", "Quit"),
        Binding("ctrl+c", "request_quit", "Quit", show=False, priority=True),
    ]

    def __init__(self, session: Session, log_dir: Path, scrollback: int = 5000,
                 sigterm_timeout: float = 5.0, sigkill_timeout: float = 5.0,
                 pane_fps: float = PANE_FPS, session_name: str | None = None,
                 owner: bool = False, keep_on_hangup: bool = False) -> None:
        no_color = os.environ.get("NO_COLOR")
        super().__init__()
        # no animated tab underlines or scrolling: every frame is bytes over ssh
        self.animation_level = "none"
        if no_color is not None:
            # Textual takes NO_COLOR out of the environment; the nodes should still see it
            os.environ["NO_COLOR"] = no_color
        self.session = session
        self.log_dir = log_dir
        self.scrollback = scrollback
        self.sigterm_timeout = sigterm_timeout
        self.sigkill_timeout = sigkill_timeout
        self.pane_fps = pane_fps
        self.store = OutputStore(scrollback=scrollback, all_scrollback=scrollback * 4)
        # lines taken per drain tick at most: 10 ticks/s x 2500 is more than anyone reads;
        # the rest is counted on screen and kept in the log files
        self.buffer = EventBuffer(max_lines=2500)
        self.supervisor: Supervisor | RemoteSupervisor | None = None
        # with a session name the launch runs in a session server and this app is a client
        self.session_name = session_name
        self.owner = owner
        self.keep_on_hangup = keep_on_hangup
        self.detached = False
        self._own_relaunch: list[str] | None = None
        self.preview: Preview | None = None
        self.exit_status = 0
        self.quitting = False
        self.terminal_lost = False
        self._bridge: RosBridge | None = None
        self._bridge_lock = threading.Lock()
        # stops the operator asked for: their non-zero exit is not a failure
        self._stopping: set[str] = set()
        self._quit_started: float | None = None
        self._status_text = ""
        self._detail_text = ""

    # --- layout ----------------------------------------------------------------------

    def compose(self) -> ComposeResult:
        yield Static("", id="status")
        with LaunchTabs(initial="nodes"):
            with TabPane("1 Nodes", id="nodes"), Vertical(id="nodes-tab"):
                yield Static("", id="detail")
                with NodesView(id="nodes-split"):
                    yield LaunchTree(id="tree")
                    yield OutputPanel(self.store, self.log_dir, max_lines=self.scrollback,
                                      max_fps=self.pane_fps, id="output")
            with TabPane("2 Args", id="args"):
                yield ArgsPanel(self.session.plan.arguments, self.session.plan.file,
                                id="args-panel")
            with TabPane("3 Services", id="services"):
                yield ServicesPanel(self.bridge, id="services-panel")
            with TabPane("4 Params", id="params"):
                yield ParamsPanel(self.bridge, lambda: self.session.plan,
                                  reported=lambda: self.store.reported_names,
                                  id="params-panel")
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
        self.detail_bar = self.query_one("#detail", Static)
        self.launch_tree.reported = self.store.reported_names
        # the engine thread reads floods; a shorter GIL slice lets keypresses through sooner
        sys.setswitchinterval(0.001)
        self.engine = EngineThread()
        # built on the engine thread, whose loop its asyncio objects belong to
        if self.session_name is not None:
            remote = self.engine.submit(RemoteSupervisor.open(
                self.session_name, self.session, self.scrollback,
                max_lines=self.buffer.max_lines, interval=1 / DRAIN_HZ)).result(timeout=60)
            remote.owner, remote.keep_on_hangup = self.owner, self.keep_on_hangup
            self.supervisor = remote
        else:
            self.supervisor = self.engine.call(lambda: Supervisor(
                self.session.plan, self.log_dir, sigterm_timeout=self.sigterm_timeout,
                sigkill_timeout=self.sigkill_timeout, bridge_factory=self.bridge))
        assert self.supervisor is not None
        self.supervisor.subscribe(self.buffer)
        tree = self.launch_tree
        tree.show_plan(self.session.plan, self.supervisor.states)
        self._describe_waiting()
        if isinstance(self.supervisor, RemoteSupervisor):
            self.show_events(self.supervisor.history)  # what was printed before we came
            for process, state in self.supervisor.lifecycle.states.items():
                tree.set_lifecycle(process, state)  # states reached before we came
        self.run_supervisor()
        self._drain_timer = self.set_interval(1 / DRAIN_HZ, self.drain)
        loop = asyncio.get_running_loop()
        loop.add_signal_handler(signal.SIGTERM, self._terminated)
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
            self._kill_all()
            self.engine.stop()
        if self._bridge is not None:
            self._bridge.close()
            self._bridge = None

    def _kill_all(self) -> None:
        """SIGKILL what is left, on the engine's thread: the supervisor (its process table,
        its watchdog pipe) belongs to that thread while its loop runs."""
        assert self.supervisor is not None
        if self.engine.loop.is_running():
            try:
                self.engine.call(self.supervisor.kill_all)
                return
            except Exception:
                pass  # the loop ended meanwhile: nothing runs there any more
        self.supervisor.kill_all()

    # --- engine events -------------------------------------------------------------------

    def drain(self) -> None:
        self.show_events(self.buffer.drain())

    def show_events(self, events: list[Event]) -> None:
        tree = self.launch_tree
        panel = self.output_panel
        fresh: list[Line] = []
        for event in events:
            if event.kind == "output" and event.process:
                fresh += self.store.add(event.process, event.stream or "stdout", event.lines)
            elif event.kind == "log":
                if event.process and self.supervisor is not None:
                    tree.set_state(event.process, self.supervisor.states.get(event.process, ""))
                level = {"WARN": WARN, "ERROR": ERROR}.get(event.level, INFO)
                fresh += self.store.add_event(event.process or "launch", event.reason or "",
                                              level)
            elif event.kind == "lifecycle" and event.process:
                tree.set_lifecycle(event.process, event.reason or "")
                self.refresh_bindings()
            elif event.kind == "component" and event.data:
                data = event.data
                short = f"id {data['unique_id']}" if "unique_id" in data else \
                    str(data.get("error") or data.get("text") or "")
                tree.set_component(str(data["component"]), str(data["state"]), short)
                if data["state"] not in ("loading", "waiting"):
                    level = {"WARN": WARN, "ERROR": ERROR}.get(event.level, INFO)
                    fresh += self.store.add_event(event.process or "launch",
                                                  event.reason or "", level)
            elif event.kind == "relaunched" and self.supervisor is not None:
                # any client's relaunch: the session already holds the new plan
                tree.show_plan(self.session.plan, self.supervisor.states)
                self._describe_waiting()
                if event.lines != self._own_relaunch:
                    self._relaunched_elsewhere(event.lines)
                self._own_relaunch = None
            elif event.kind == "dropped" and event.process:
                # counted in the pane's status line, not written as lines of their own
                self.store.count_dropped(event.process, event.code or 0)
            elif event.process and self.supervisor is not None:
                fresh += self._process_event(event)
        if fresh:
            panel.append(fresh)
        panel.flush()
        if events:
            self.update_status()
            self.update_detail()
        elif self._quit_started is not None:
            self.update_status()  # the signal stage moves on with time

    def _process_event(self, event: Event) -> list[Line]:
        """A state change: the tree row, and a line in the node's pane as ros2 launch
        prints it ("process started with pid", "process has died [pid, exit code]")."""
        assert self.supervisor is not None and event.process is not None
        process = event.process
        tree = self.launch_tree
        state = self.supervisor.states.get(process, event.kind)
        is_process = any(p.id == process for p in self.session.plan.processes)
        if event.kind == "started":
            self._stopping.discard(process)
            tree.set_state(process, state, f"pid {event.pid}" if event.pid else "")
            if is_process:
                return self.store.add_event(process, f"process started with pid [{event.pid}]")
            return []
        if event.kind == "exited":
            code = event.code if event.code is not None else 0
            # the server says whether anyone asked for the stop (another client, a
            # `tuilaunch stop`, a stop begun before this client attached)
            asked = process in self._stopping or self.quitting or bool(
                event.data and event.data.get("requested"))
            if code != 0 and not asked and state == "exited":
                state = "failed"  # a crash, not the operator's stop
            tree.set_state(process, state, f"({event.reason}, pid {event.pid})")
            if code == 0:
                text, level = f"process has finished cleanly [pid {event.pid}]", INFO
            elif asked:
                text, level = f"process stopped [pid {event.pid}, {event.reason}]", INFO
            else:
                text, level = f"process has died [pid {event.pid}, {event.reason}]", ERROR
            return self.store.add_event(process, text, level)
        if event.kind == "failed":
            tree.set_state(process, state, f"({event.reason})")
            return self.store.add_event(process, f"failed: {event.reason}", ERROR)
        if event.kind == "respawning":
            tree.set_state(process, state, f"({event.reason})")
            return self.store.add_event(process, f"respawning: {event.reason}", WARN)
        tree.set_state(process, state, _detail(event))
        return []

    def _relaunched_elsewhere(self, arguments: list[str]) -> None:
        """Another operator applied new values: the form shows them, so an edit here starts
        from what runs, never silently reverts theirs."""
        self.preview = None
        self.launch_tree.set_preview(None)
        self.args_panel.arguments = self.session.plan.arguments
        self.args_panel.refresh(recompose=True)
        self.notify(f"relaunched by another client: {' '.join(arguments) or 'defaults'}")
        self.refresh_bindings()

    def update_status(self) -> None:
        if self.supervisor is None:
            return
        counts: dict[str, int] = {}
        shown = self.launch_tree.states
        for proc in self.session.plan.processes:
            state = shown.get(proc.id) or self.supervisor.states.get(proc.id, "pending")
            counts[state] = counts.get(state, 0) + 1
        order = ("running", "pending", "stopping", "exited", "failed", "respawning", "skipped")
        text = "  ".join(f"{counts[s]} {'waiting' if s == 'pending' else s}" for s in order
                         if counts.get(s))
        args = " ".join(f"{k}:={v}" for k, v in self.session.arguments.items())
        prefix = ""
        if self.quitting:
            still = self.running()
            prefix = f"stopping {', '.join(still)} ({self._signal_stage()})... " if still \
                else "stopped. "
        name = Path(self.session.plan.file).name
        if self.session_name is not None:
            name = f"[{self.session_name}] {name}"
        line = f"{prefix}{name}  {text}  {args}"
        if line != self._status_text:  # an unchanged line is not sent to the terminal again
            self._status_text = line
            self.status_bar.update(Text(line))

    def _signal_stage(self) -> str:
        """Where the SIGINT -> SIGTERM -> SIGKILL escalation is, from the timeouts."""
        if self._quit_started is None:
            return "SIGINT sent"
        elapsed = time.monotonic() - self._quit_started
        if elapsed < self.sigterm_timeout:
            return f"SIGINT sent, SIGTERM in {self.sigterm_timeout - elapsed:.0f} s; q: kill now"
        elapsed -= self.sigterm_timeout
        if elapsed < self.sigkill_timeout:
            return f"SIGTERM sent, SIGKILL in {self.sigkill_timeout - elapsed:.0f} s; " \
                   "q: kill now"
        return "SIGKILL sent"

    def update_detail(self) -> None:
        """The selected row in full, above the tree and the pane: state, pid, exit code,
        failure reason or condition, whatever the tree's width cuts."""
        node = self.launch_tree.cursor_node
        text = self.launch_tree.describe(node) if node is not None else ""
        if text != self._detail_text:
            self._detail_text = text
            self.detail_bar.update(Text(text, style=_detail_style(text)))

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
        self.update_detail()
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
        if action == "detach":
            return self.session_name is not None
        if action == "lifecycle":
            if self.supervisor is None or self.tabs.active != "nodes":
                return False
            selected = self.selected()
            # shown only while a lifecycle node is selected: other launches keep their footer
            if len(selected) != 1 or selected[0] not in self.supervisor.lifecycle.states:
                return False
            return True if self._lifecycle_step(str(parameters[0])) else None
        return True

    def _command(self, verb: str) -> None:
        assert self.supervisor is not None
        supervisor = self.supervisor
        processes = self.selected()
        node = self.launch_tree.cursor_node
        everything = node is not None and node.data is not None and (
            node.data.kind == "all" or node is self.launch_tree.root)
        if verb == "stop" and everything and len(processes) > 1:
            running = [p for p in processes if supervisor.states.get(p) == "running"]

            def answered(yes: bool | None) -> None:
                if yes:
                    self._run_command(verb, processes)

            self.push_screen(ConfirmScreen(
                f"Stop all {len(running)} running processes: {', '.join(running[:6])}"
                f"{' ...' if len(running) > 6 else ''}?", "Stop them (y)"), answered)
            return
        self._run_command(verb, processes)

    def _run_command(self, verb: str, processes: list[str]) -> None:
        assert self.supervisor is not None
        supervisor = self.supervisor
        tree = self.launch_tree
        commands = []
        for process in processes:
            if verb in ("stop", "restart"):
                self._stopping.add(process)
                if supervisor.states.get(process) == "running":
                    tree.set_state(process, "stopping")
            commands.append(getattr(supervisor, verb)(process))
        actions = self._actions_to_rerun(processes) if verb in ("restart", "start") else []
        self.run_worker(self._carry_out(commands, actions), group="commands",
                        exit_on_error=False)
        self.refresh_bindings()

    async def _carry_out(self, commands: list[Any], actions: list[str]) -> None:
        """The commands together; then the group's actions (set_parameters, call_service)
        again, so a restarted node gets what the launch file gave it after its start."""
        assert self.supervisor is not None
        await asyncio.gather(*(self.engine.run(c) for c in commands))
        for action in actions:
            self.run_worker(self.engine.run(self.supervisor.run_action(action)),
                            group="commands", exit_on_error=False)

    def _actions_to_rerun(self, processes: list[str]) -> list[str]:
        """The enabled one-off actions of the selected group, or for one node those of its
        group that wait for it or address it by name."""
        node = self.launch_tree.cursor_node
        if node is None or node.data is None or node.data.kind == "action":
            return []
        plan = self.session.plan
        enabled = {a.id: a for a in plan.actions if a.enabled and a.kind in (
            "set_parameters", "call_service") and (a.trigger is None or a.trigger.on not in (
                "io", "shutdown"))}
        if node.data.kind in ("group", "all"):
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
            addressed = action.kind == "set_parameters" and str(action.target) in names
            if waits_for or addressed:
                chosen.append(ref)
        return chosen

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
        if self.tabs.active != tab:
            self.tabs.active = tab
            self._enter_tab(tab)
        self.refresh_bindings()

    def on_key(self, event: events.Key) -> None:
        """ESC and a key read together arrive as one key (see fields.py): outside a field,
        where escape leaves nothing, that is the key alone. Not in a dialog: there escape
        answers no, and the key must not answer again."""
        following = after_escape(event)
        if following is None or isinstance(self.screen, ModalScreen):
            return
        event.stop()
        if following.key in ("1", "2", "3", "4"):
            self.action_tab(("nodes", "args", "services", "params")[int(following.key) - 1])
        else:
            self.post_message(following)

    def action_leave_field(self) -> None:
        """Escape in a text field: out of it, to where the tab's work starts, so the next
        keys (1-4, s, q, ...) are commands again. The focus moves at once, not on the next
        tick, so keys typed right after escape go to the new place."""
        focused = self.focused
        if isinstance(focused, Field) and focused.id in ("search-input", "filter-input"):
            self.output_panel.action_clear_search()
            self.screen.set_focus(self.output_panel.line_view)
            return
        self.screen.set_focus(self._home(self.tabs.active))

    def _home(self, pane: str) -> Widget:
        if pane == "args":
            return self.query_one("#apply", Button)
        if pane == "services":
            return self.query_one("#svc-list", OptionList)
        if pane == "params":
            return self.query_one("#prm-nodes", OptionList)
        return self.launch_tree

    @on(TabbedContent.TabActivated)
    def _tab_changed(self, event: TabbedContent.TabActivated) -> None:
        self.refresh_bindings()
        pane = event.pane.id or "nodes"
        focused = self.focused
        if not (isinstance(focused, Widget) and pane_of(focused) == pane):
            self._enter_tab(pane)  # a click on a tab: the keys did this already

    def _enter_tab(self, pane: str) -> None:
        """Keyboard first: each tab puts the cursor where work starts, at once, so keys
        typed right after the tab key go there; again once the tab is laid out."""
        target: Widget | None = None
        if pane == "nodes":
            target = self.launch_tree
        elif pane == "args":
            editors = self.args_panel.query(".arg-editor")
            target = editors.first() if editors else self.query_one("#apply", Button)
        elif pane == "services":
            self.query_one(ServicesPanel).refresh_services()
            target = self.query_one("#svc-filter")
        elif pane == "params":
            self.query_one(ParamsPanel).refresh_nodes()
            target = self.query_one("#prm-filter")
        if target is not None:
            self.screen.set_focus(target)
            self.call_after_refresh(self._refocus, pane, target)

    def _refocus(self, pane: str, target: Widget) -> None:
        if not self.is_running or not self.screen_stack:
            return
        if self.tabs.active == pane and self.focused is not target and not (
                isinstance(self.focused, Widget) and pane_of(self.focused) == pane):
            self.screen.set_focus(target)

    def action_help(self) -> None:
        self.push_screen(HelpScreen())

    # --- arguments ---------------------------------------------------------------------------

    @on(ArgsPanel.Edited)
    def _args_edited(self, event: ArgsPanel.Edited) -> None:
        self.preview_values(event.values)

    def preview_values(self, values: dict[str, str]) -> None:
        """What these form values would do; a value the plan cannot use is an error here,
        and F5 never applies it."""
        current = {a.name: a.value for a in self.session.plan.arguments}
        edits = {k: v for k, v in values.items() if v != current.get(k)}
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
        problem = check_values(self.session.plan.arguments, edits)
        if problem is None:
            self.preview = self.session.preview(edits, running)
            if self.preview.plan is not None:
                problem = check_plan(self.preview.plan)
        else:
            self.preview = Preview({**self.session.arguments, **edits}, None, None, problem)
        if problem is not None:
            self.preview = Preview(self.preview.arguments, None, None, problem)
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
        # the form as it is now: keys typed just before F5 may not have been previewed yet
        self.preview_values(self.args_panel.values())
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
        self._own_relaunch = [f"{k}:={v}" for k, v in self.session.arguments.items()]
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
        if self.quitting:
            if running and not isinstance(self.screen, ConfirmScreen):
                self._offer_kill(running)
            return
        if not running:
            self.stop_all_and_exit()
            return

        def answered(stop: bool | None) -> None:
            if stop:
                self.stop_all_and_exit()

        self.push_screen(QuitScreen(running), answered)

    async def action_quit(self) -> None:
        self.action_request_quit()

    def _offer_kill(self, running: list[str]) -> None:
        """A second q while stubborn processes stop: SIGKILL them now, or keep waiting."""
        def answered(yes: bool | None) -> None:
            if yes and self.supervisor is not None:
                self._kill_all()

        self.push_screen(ConfirmScreen(
            f"Still stopping: {', '.join(running[:6])} ({self._signal_stage()}).\n"
            "Kill them now with SIGKILL?", "Kill now (y)", "Keep waiting (n)"), answered)

    def _terminal_hung_up(self) -> None:
        """SIGHUP: the ssh session or tmux pane is gone. An attached session, or one started
        with --keep-on-hangup, runs on; otherwise everything stops, then the app leaves. The
        server does the stopping, so the launch is never left half-stopped."""
        self.terminal_lost = True
        if self.session_name is not None and (self.keep_on_hangup or not self.owner):
            self.action_detach()
        else:
            self.stop_all_and_exit("the terminal hung up (SIGHUP)")

    def _terminated(self) -> None:
        """SIGTERM stops what this app started; a client that only attached just leaves."""
        if self.session_name is not None and not self.owner:
            self.action_detach()
        else:
            self.stop_all_and_exit("SIGTERM")

    def action_detach(self) -> None:
        """Leaves the session running; the supervisor worker then exits the app."""
        if not isinstance(self.supervisor, RemoteSupervisor):
            self.notify("only a session can be detached from", severity="warning")
            return
        self.detached = True
        self.run_worker(self.engine.run(self.supervisor.detach()), group="shutdown",
                        exit_on_error=False)

    def stop_all_and_exit(self, reason: str = "quit from the UI") -> None:
        """Shutdown escalation runs; the supervisor worker exits the app when all are gone.
        The reason goes into launch.log, so a stop nobody asked for at the keyboard is told
        apart later."""
        if self.supervisor is None:
            self.exit(0)
            return
        self.quitting = True
        self._quit_started = time.monotonic()
        for process in self.running():
            self.launch_tree.set_state(process, "stopping")
        self.update_status()
        self.run_worker(self.engine.run(self.supervisor.shutdown(reason)),
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
        if self.session_name is not None:
            yield SystemCommand("Detach", "Leave the launch running (tuilaunch attach)",
                                self.action_detach)
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
    if event.kind == "started" and event.pid is not None:
        return f"pid {event.pid}"
    if event.kind in ("exited", "failed", "respawning") and event.reason:
        return f"({event.reason})"
    return ""


def pane_of(widget: Widget) -> str | None:
    """The id of the tab pane a widget is in."""
    for node in widget.ancestors_with_self:
        if isinstance(node, TabPane):
            return node.id
    return None


def _detail_style(text: str) -> str:
    if ": failed" in text or "refused" in text:
        return "bold red"
    return ""


def _action_refs(node: Any) -> list[str]:
    """Action ids in a tree row's subtree, in the tree's order."""
    refs = []
    for child in node.children:
        data = child.data
        if data is not None and data.kind == "action" and data.ref:
            refs.append(data.ref)
        refs += _action_refs(child)
    return refs


def _trigger_targets(trigger: Any, process: str) -> bool:
    while trigger is not None:
        if trigger.target == process:
            return True
        trigger = trigger.after
    return False


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
