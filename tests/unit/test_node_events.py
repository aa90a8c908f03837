"""The Nodes tab over a session's view (session_view.py), in a small host app (no process,
no ROS graph): the view shows the events as the app's drain hands them, and a process's
life shows in its row and its pane in ros2 launch's words; the app hears what changed.
The fleet view shows each session through the same view (tests/integration/test_fleet_tui.py)."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

from textual.app import App, ComposeResult

from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.events import (
    Event,
    ExitCause,
    LifecycleChanged,
    Output,
    ProcessExited,
    Relaunched,
    Respawning,
    Started,
)
from tuilaunch.tui.nodes.events import Batch
from tuilaunch.tui.nodes.tab import NodesTab
from tuilaunch.tui.output_store import OutputStore, View
from tuilaunch.tui.screens.output_panel import OutputPanel
from tuilaunch.tui.screens.tree_panel import LaunchTree
from tuilaunch.tui.session_view import SessionView

LAUNCH = """
from launch import LaunchDescription
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        Node(package='demo', executable='talker', name='talker'),
        Node(package='demo', executable='listener', name='listener'),
    ])
"""


class Lifecycle:
    def __init__(self) -> None:
        self.states: dict[str, str] = {}


class Client:
    """What the tab reads of a session's client: its states, its lifecycle states."""

    def __init__(self, session: Session) -> None:
        self.states = {p.id: "pending" for p in session.plan.processes}
        self.lifecycle = Lifecycle()


class Host(App[None]):
    """Holds a session's view as the TUI does, and the Nodes tab over it."""

    def __init__(self, session: Session) -> None:
        super().__init__()
        self.session = session
        self.engine: Any = None
        self.read_only = False
        self.quitting = False
        self.store = OutputStore()
        self.view = SessionView("", None, "demo", LaunchTree(id="tree"), OutputPanel(
            self.store, Path("."), max_lines=100, max_fps=100.0, id="output"), self.store,
            self, session)
        self.supervisor: Any = Client(session)
        self.view.supervisor = self.supervisor
        self.asked_to_stop = self.view.asked_to_stop
        self.heard: list[tuple[Batch, bool]] = []
        """What each batch changed, and whether it was a replay."""

    def compose(self) -> ComposeResult:
        yield NodesTab(self.view, lambda: None)

    def on_mount(self) -> None:
        self.query_one(NodesTab).events.show_plan()

    def update_status(self) -> None:
        pass

    async def show_typing_line(self, line: Any) -> None:
        pass

    def send(self, *events: Event, replaying: bool = False) -> None:
        for event in events:  # the client's states change before its events are shown
            if event.process in self.supervisor.states and event.kind != "output":
                self.supervisor.states[event.process] = {
                    "started": "running", "exited": "exited",
                    "respawning": "respawning"}.get(event.kind, event.kind)
        # as the app's drain does (session_link.py)
        shown = self.view.show_events(list(events), replaying)
        self.query_one(NodesTab).batch_shown(shown, bool(events))
        self.heard.append((shown, replaying))


def session(tmp_path: Path) -> Session:
    path = tmp_path / "demo.launch.py"
    path.write_text(textwrap.dedent(LAUNCH))
    return Session(str(path), {})


def pane_lines(app: Host, process: str) -> list[str]:
    return [line.text for line in app.store.lines(View(process)) if line.event]


async def test_a_process_life_shows_in_its_row_and_its_pane_in_ros2_launch_words(tmp_path):
    app = Host(session(tmp_path))
    async with app.run_test(size=(100, 24)) as pilot:
        tab = app.query_one(NodesTab)
        talker, listener = (p.id for p in app.session.plan.processes)
        app.send(Started(talker, pid=101), Started(listener, pid=102),
                 Output(talker, stream="stdout", lines=["[INFO] [1.0] [talker]: hello"]))
        await pilot.pause()
        assert tab.launch_tree.states[talker] == "running"
        assert "pid 101" in tab.launch_tree.details[talker]
        assert pane_lines(app, talker) == ["process started with pid [101]"]
        assert any("hello" in line.text for line in app.store.lines(View(talker)))
        # nobody asked: a crash, failed; a stop asked here: stopped, no failure
        app.asked_to_stop.add(listener)
        app.send(ProcessExited(talker, pid=101, code=1, reason="exit code 1",
                               cause=ExitCause.CRASHED),
                 ProcessExited(listener, pid=102, code=-2, reason="SIGINT",
                               cause=ExitCause.CRASHED))
        await pilot.pause()
        assert tab.launch_tree.states[talker] == "failed"
        assert pane_lines(app, talker)[-1] == "process has died [pid 101, exit code 1]"
        assert tab.launch_tree.states[listener] == "exited"
        assert pane_lines(app, listener)[-1] == "process stopped [pid 102, SIGINT]"
        # the app heard of each batch, after the tab had shown it
        assert len(app.heard) == 2 and not app.heard[-1][0].lifecycle


async def test_a_respawn_wait_counts_down_on_its_row(tmp_path):
    app = Host(session(tmp_path))
    async with app.run_test(size=(100, 24)) as pilot:
        tab = app.query_one(NodesTab)
        talker = app.session.plan.processes[0].id
        app.send(Respawning(talker, reason="respawn in 3 s", data={"try": 2, "delay": 3.0}))
        await pilot.pause()
        assert tab.launch_tree.details[talker] == "(try 2 in 3 s)"
        assert pane_lines(app, talker) == ["respawning: respawn in 3 s"]
        for _ in range(60):  # once a second, on the tab's own timer
            if tab.launch_tree.details[talker] == "(try 2 in 1 s)":
                break
            await pilot.pause(0.1)
        assert tab.launch_tree.details[talker] == "(try 2 in 1 s)"
        app.send(Started(talker, pid=7))  # back: nothing more to count
        await pilot.pause()
        assert tab.launch_tree.details[talker] == "pid 7"


async def test_a_replay_keeps_the_lifecycle_states_reached_since(tmp_path):
    """What happened before the client came is shown first, then the states the client
    knows now: an old lifecycle event replayed does not undo a later state."""
    app = Host(session(tmp_path))
    async with app.run_test(size=(100, 24)) as pilot:
        tab = app.query_one(NodesTab)
        talker = app.session.plan.processes[0].id
        app.supervisor.lifecycle.states[talker] = "active"
        app.send(LifecycleChanged(talker, reason="inactive"), replaying=True)
        await pilot.pause()
        assert tab.launch_tree.lifecycle[talker] == "active"
        assert app.heard[-1][1] and app.heard[-1][0].lifecycle
        app.send(Relaunched(None, lines=["robot:=r2"]))
        await pilot.pause()
        assert [e.lines for e in app.heard[-1][0].relaunched] == [["robot:=r2"]]
