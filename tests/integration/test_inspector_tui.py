"""The inspector in the TUI, attached to a real session server running real rclpy nodes:
the Topics tab (processes, live rates, filter, QoS problems, echo), CPU and memory in the
tree, parameters written to and loaded from files, and logger levels."""

from __future__ import annotations

import os
import sys
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

import pytest
import yaml
from textual.pilot import Pilot
from textual.widgets import Input, Static

from tuilaunch.engine.run.vocabulary.request import Request
from tuilaunch.engine.run.vocabulary.requests import Topics
from tuilaunch.tui.app import TuiLaunchApp, make_app
from tuilaunch.tui.screens.dialogs import ChoiceScreen, ConfirmScreen, PathScreen
from tuilaunch.tui.screens.params_panel import ParamsPanel
from tuilaunch.tui.screens.topics_panel import TopicsPanel
from tuilaunch.tui.screens.tree_panel import LaunchTree

from .inspector_helpers import NODE_SCRIPT
from .launch_world import make_package
from .session_steps import start_here, stop_here
from .test_sessions import runtime, status, tl, wait_state  # noqa: F401
from .test_tui import row_text, tab_panel, until

# the package's executable: inspector_node.py, as a launch file's node runs it
WRAPPER = f"""#!{sys.executable}
import runpy
runpy.run_path({str(NODE_SCRIPT)!r}, run_name="__main__")
"""

# a best-effort publisher and a reliable subscriber: the QoS pair that cannot talk
LAUNCH = """
from simple_launch import SimpleLauncher

def generate_launch_description():
    sl = SimpleLauncher()
    sl.node('insp_demo', 'inspector_node', name='lidar',
            arguments=['lidar', '--pub', '/scan_tui', '--rate', '20', '--best-effort',
                       '--params'])
    sl.node('insp_demo', 'inspector_node', name='mapper',
            arguments=['mapper', '--sub', '/scan_tui'])
    sl.node('insp_demo', 'inspector_node', name='chatter',
            arguments=['chatter', '--pub', '/chat_tui', '--rate', '10', '--logger-service'])
    return sl.launch_description()
"""


@pytest.fixture
def demo(runtime, tmp_path, monkeypatch):  # noqa: F811
    """The launch file, its package of rclpy nodes on AMENT_PREFIX_PATH."""
    prefix = tmp_path / "prefix"
    make_package(prefix, "insp_demo", ["inspector_node"], probe=WRAPPER)
    monkeypatch.setenv("AMENT_PREFIX_PATH",
                       os.pathsep.join([str(prefix), os.environ.get("AMENT_PREFIX_PATH", "")]))
    path = tmp_path / "insp_launch.py"
    path.write_text(LAUNCH)
    return path


@asynccontextmanager
async def session_tui(path: Path, size: tuple[int, int] = (120, 36))\
        -> AsyncIterator[tuple[TuiLaunchApp, Pilot]]:
    """The launch in a session server (as `tuilaunch FILE` runs it) and the TUI attached."""
    name = start_here(str(path))
    try:
        for process in ("lidar-1", "mapper-2", "chatter-3"):
            wait_state(name, process, "running")
        log_dir = Path(status(name)["log_dir"])
        app = make_app(str(path), {}, log_dir, session_name=name)
        async with app.run_test(size=size) as pilot:
            yield app, pilot
    finally:
        stop_here(name, gone_ok=True)


def detail(app: TuiLaunchApp) -> str:
    return app.query_one(TopicsPanel).detail_text


def cell(app: TuiLaunchApp, topic: str, column: str) -> str:
    panel = app.query_one(TopicsPanel)
    return panel.cells.get((topic, column), "")


async def test_topics_tab_lists_processes_rates_problems_and_echoes(demo):
    async with session_tui(demo) as (app, pilot):
        panel = await tab_panel(pilot, app, "5", TopicsPanel)
        await until(pilot, lambda: {"/scan_tui", "/chat_tui"} <= set(panel.shown))
        # the publishing process is named, with the QoS it offers
        panel.table.move_cursor(row=panel.shown.index("/scan_tui"))
        # (/parameter_events names every process too: the detail must be /scan_tui's)
        await until(pilot, lambda: detail(app).startswith("/scan_tui")
                    and "[lidar-1]" in detail(app) and "[mapper-2]" in detail(app))
        assert "best_effort" in detail(app)
        # the pair that cannot talk is marked in its row and said in a sentence
        assert cell(app, "/scan_tui", "qos") != ""
        assert cell(app, "/chat_tui", "qos") == ""
        problem = next(line for line in detail(app).splitlines() if "/mapper" in line
                       and "/lidar" in line and "reliab" in line.lower())
        assert problem
        # a rate for the rows on screen, live
        await until(pilot, lambda: cell(app, "/chat_tui", "rate").endswith("Hz")
                    and cell(app, "/chat_tui", "rate") != "0.0 Hz")
        assert "/chat_tui" in panel.watched
        rate = float(cell(app, "/chat_tui", "rate").split()[0])
        assert 3 < rate < 30  # published at 10 Hz; the bench measures the accuracy

        # the filter narrows the rows as one types
        await pilot.press("slash", *"chat")
        await until(pilot, lambda: panel.shown == ["/chat_tui"])
        assert "/scan_tui" not in panel.rows_on_screen()
        await pilot.press("enter")  # back to the table, the filter stays
        assert app.focused is panel.table

        # echo: the messages as YAML, stopped by e again and by leaving the tab
        await pilot.press("e")
        await until(pilot, lambda: "data: hello" in detail(app))
        assert panel.echo_topic == "/chat_tui"
        await pilot.press("1")
        assert panel.echo_topic is None and panel.watched == []

        # from the Nodes tab, o shows the selected node's topics only
        tree = app.query_one(LaunchTree)
        tree.move_cursor(tree.rows["mapper-2"])
        await pilot.pause()
        await pilot.press("o")
        assert app.tabs.active == "topics" and panel.node == "/mapper"
        await pilot.press("x")  # the filter field is cleared first: then every topic
        await until(pilot, lambda: panel.node is None)


async def test_tree_shows_cpu_memory_and_qos_problems_while_the_nodes_tab_is_shown(demo):
    async with session_tui(demo) as (app, pilot):
        tree = app.query_one(LaunchTree)
        assert app.inspector.watching_resources
        # the tree is too narrow for the figures: only the selected process's are sent,
        # for the detail line, and with the root selected none
        tree.move_cursor(tree.rows["lidar-1"])
        await pilot.pause()
        # its figures, not only the minutes kept before (the sparklines, which can come
        # first on a loaded machine)
        await until(pilot, lambda: "threads" in str(app.query_one("#detail", Static).render()))
        line = str(app.query_one("#detail", Static).render())
        assert "cpu " in line and "mem " in line
        assert set(tree.usage) == {"lidar-1"}
        tree.move_cursor(tree.rows["chatter-3"])
        await until(pilot, lambda: set(tree.usage) == {"chatter-3"})
        await until(pilot, lambda: "threads" in str(app.query_one("#detail", Static).render()))
        tree.move_cursor(tree.rows["lidar-1"])
        # a tree wide enough shows them in the rows: every process's are sent
        assert tree.size.width < 44 and "%" not in row_text(app, "lidar-1")
        for _ in range(4):
            await pilot.press("greater_than_sign")
        await until(pilot, lambda: {"lidar-1", "mapper-2", "chatter-3"} <= set(tree.usage))
        await until(pilot, lambda: "%" in row_text(app, "lidar-1")
                    and "%" in row_text(app, "mapper-2"))
        # both nodes of the pair that cannot talk are marked, and the detail says why
        await until(pilot, lambda: "✗qos" in row_text(app, "mapper-2")
                    and "✗qos" in row_text(app, "lidar-1"))
        assert "✗qos" not in row_text(app, "chatter-3")
        await until(pilot, lambda: "QoS: " in str(app.query_one("#detail", Static).render()))
        assert "/mapper" in str(app.query_one("#detail", Static).render())
        # leaving the tab stops the sampling: no figures that no longer move
        await pilot.press("3")
        await until(pilot, lambda: not tree.usage)
        assert not app.inspector.watching_resources
        await pilot.press("escape", "1")  # out of the services filter, back to the tree
        await until(pilot, lambda: "lidar-1" in tree.usage)


async def test_log_level_key_sets_it_or_offers_a_restart(demo):
    async with session_tui(demo) as (app, pilot):
        tree = app.query_one(LaunchTree)
        tree.move_cursor(tree.rows["chatter-3"])
        await pilot.pause()
        await pilot.press("L")
        await until(pilot, lambda: isinstance(app.screen, ChoiceScreen))
        await pilot.press("d")  # debug
        await until(pilot, lambda: app.inspector.log_levels.levels.get("chatter-3") == "debug")

        # a node without the logger service: the restart with --log-level is offered
        tree.move_cursor(tree.rows["mapper-2"])
        await pilot.pause()
        await pilot.press("L", "w")
        # pushed, then composed: the question is there once its Static is
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen)
                    and bool(app.screen.query(Static)), limit=60)
        question = str(app.screen.query_one(Static).render())
        assert "no logger service" in question and "--log-level warn" in question
        old_pid = status(app.session_name or "")
        before = next(p["pid"] for p in old_pid["processes"] if p["id"] == "mapper-2")
        await pilot.press("y")
        await until(pilot, lambda: app.inspector.log_levels.levels.get("mapper-2") == "warn",
                    limit=60)

        def restarted() -> bool:
            now = status(app.session_name or "")
            entry = next(p for p in now["processes"] if p["id"] == "mapper-2")
            return entry["state"] == "running" and entry["pid"] != before

        await until(pilot, restarted, limit=60)
        # the node now runs with the level, as `ros2 run ... --ros-args --log-level warn`
        now = status(app.session_name or "")
        command = next(p["command"] for p in now["processes"] if p["id"] == "mapper-2")
        assert command[-3:] == ["--ros-args", "--log-level", "warn"]


async def test_params_tab_writes_and_loads_a_params_file(demo, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    async with session_tui(demo) as (app, pilot):
        panel = await tab_panel(pilot, app, "4", ParamsPanel)
        panel.load_node("/lidar")
        await until(pilot, lambda: "gains.p" in panel.params, every=None)
        app.screen.set_focus(panel.query_one("#prm-nodes"))
        await pilot.press("w")
        await until(pilot, lambda: isinstance(app.screen, PathScreen))
        assert app.screen.query_one(Input).value == "./lidar.yaml"
        await pilot.press("enter")
        written = tmp_path / "lidar.yaml"
        await until(pilot, written.exists)
        values = yaml.safe_load(written.read_text())["/lidar"]["ros__parameters"]
        assert values["rate"] == 10.0 and values["label"] == "lidar"
        assert values["gains"] == {"p": 1.5, "i": 0.25}

        # load a changed copy: each parameter's answer is shown, the table follows
        values["label"] = "front_lidar"
        (tmp_path / "changed.yaml").write_text(yaml.safe_dump(
            {"/lidar": {"ros__parameters": {"label": "front_lidar", "gains": {"p": 3.0}}}}))
        await pilot.press("o")
        await until(pilot, lambda: isinstance(app.screen, PathScreen))
        await pilot.press(*"changed.yaml", "enter")
        result = panel.query_one("#prm-result", Static)
        await until(pilot, lambda: "2 set" in str(result.render()))
        assert "ok label" in str(result.render()) and "ok gains.p" in str(result.render())
        await until(pilot, lambda: panel.params["label"].value == "front_lidar")


async def test_an_empty_topic_list_says_discovery_goes_on():
    """No topic yet (a launch whose nodes are still being discovered): the note says the
    list is asked again, rather than "0 topics" as if there were none."""
    from textual.app import App, ComposeResult

    late = {"name": "/late", "types": ["std_msgs/msg/String"], "publishers": [],
            "subscribers": []}
    answers: list[list[dict[str, object]]] = [[], [late]]

    async def request(asked: Request[object]) -> object:
        if isinstance(asked, Topics):
            return {"topics": answers.pop(0) if len(answers) > 1 else answers[0]}
        return {}

    class Host(App[None]):
        def compose(self) -> ComposeResult:
            yield TopicsPanel(request)

    app = Host()
    async with app.run_test(size=(100, 30)) as pilot:
        panel = app.query_one(TopicsPanel)
        panel.set_shown(True)
        note = app.query_one("#tpc-note")
        await until(pilot, lambda: str(note.render()).startswith(
            "no topic yet, discovering (asked every 3 s)"))
        # asked again by the panel itself: the topic that came is listed and counted
        await until(pilot, lambda: panel.shown == ["/late"])
        assert str(note.render()).startswith("1 topic;")
