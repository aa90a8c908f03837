"""One snapshot per dialog and per graph tab, each in a small host app at 80x24 (no
process, no ROS graph: the tabs ask a graph that answers as a session does). The Nodes and
Args tabs, which need a session, are snapshotted over a real one in
tests/integration/test_tui.py."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import pytest
from textual.app import App, ComposeResult
from textual.screen import Screen
from textual.widget import Widget

from tuilaunch.client.inspect.session_graph import field_info
from tuilaunch.engine.run.vocabulary.request import Request
from tuilaunch.engine.run.vocabulary.requests import Topics
from tuilaunch.tui.inspect.log_levels import LEVELS
from tuilaunch.tui.screens.dialogs import (
    ChoiceScreen,
    ConfirmScreen,
    HelpScreen,
    PathScreen,
    QuitScreen,
)
from tuilaunch.tui.screens.interact_dialogs import CommandScreen, PrefixPrompt, TerminalQuestion
from tuilaunch.tui.screens.params_panel import ParamsPanel
from tuilaunch.tui.screens.plot_pickers import FieldPicker
from tuilaunch.tui.screens.services_panel import ServicesPanel
from tuilaunch.tui.screens.topics_panel import TopicsPanel

SIZE = (80, 24)


class Over(App[None]):
    """A plain screen with a dialog pushed over it, as the TUI shows one."""

    def __init__(self, dialog: Callable[[], Screen[Any]]) -> None:
        super().__init__()
        self.dialog = dialog

    def on_mount(self) -> None:
        self.push_screen(self.dialog())


DIALOGS: dict[str, Callable[[], Screen[Any]]] = {
    "help": HelpScreen,
    "quit": lambda: QuitScreen(["talker-1", "listener-2"], detach=True),
    "confirm": lambda: ConfirmScreen("Stop all 2 running processes: talker-1, listener-2?",
                                     "Stop them (y)"),
    "log_level": lambda: ChoiceScreen("Log level of /r1/talker (talker-1):", LEVELS, "info"),
    "params_file": lambda: PathScreen("Write /r1/talker's parameters to", "talker.yaml"),
    "terminal": lambda: TerminalQuestion(
        "talker-1 has no terminal to type into. Restart it with a terminal and type into "
        "it?", "Restart it (y)"),
    "tool": lambda: PrefixPrompt("talker-1", ["gdb -ex run --args", "valgrind"]),
    "command": lambda: CommandScreen("talker-1", "env -- ROS_DOMAIN_ID=3 /opt/demo/talker "
                                     "--ros-args -r __node:=talker -r __ns:=/r1"),
    "plot_fields": lambda: FieldPicker([(f, f) for f in ("linear.x", "linear.y", "angular.z")],
                                       ["linear.x"]),
}


@pytest.mark.parametrize("name", DIALOGS)
def test_dialog_snapshot(snap_compare, name: str):
    assert snap_compare(Over(DIALOGS[name]), terminal_size=SIZE)


class Graph:
    """A ROS graph that answers as a session does, always the same."""

    async def list_nodes(self) -> list[str]:
        return ["/r1/listener", "/r1/talker"]

    async def list_services(self) -> list[tuple[str, list[str]]]:
        return [("/r1/enable", ["std_srvs/srv/SetBool"]), ("/r1/reset", ["std_srvs/srv/Empty"])]

    async def service_fields(self, type_name: str) -> list[Any]:
        return [field_info({"name": "data", "type": "boolean", "default": False,
                            "is_sequence": False})]


async def topics(request: Request[Any]) -> dict[str, Any]:
    if isinstance(request, Topics):
        return {"topics": [
            {"name": "/r1/chatter", "types": ["std_msgs/msg/String"], "publishers": [{}],
             "subscribers": [{}, {}]},
            {"name": "/rosout", "types": ["rcl_interfaces/msg/Log"], "publishers": [{}] * 3,
             "subscribers": []}]}
    return {}


class Tab(App[None]):
    def __init__(self, panel: Callable[[], Widget]) -> None:
        super().__init__()
        self.panel = panel

    def compose(self) -> ComposeResult:
        yield self.panel()


TABS: dict[str, Callable[[], Widget]] = {
    "services": lambda: ServicesPanel(Graph),
    "params": lambda: ParamsPanel(Graph, lambda: None),  # type: ignore[arg-type, return-value]
    "topics": lambda: TopicsPanel(topics),
}


async def settled(pilot) -> None:
    """The panel's first listing shown (asked on a worker)."""
    await pilot.app.workers.wait_for_complete()
    await pilot.pause()


@pytest.mark.parametrize("name", TABS)
def test_tab_snapshot(snap_compare, name: str):
    def shown(pilot):
        panel = pilot.app.query_one(TopicsPanel) if name == "topics" else None
        if panel is not None:
            panel.set_shown(True)
            # its first listing only: the rates, asked a second later, would come or not
            # depending on how busy the machine is
            panel.timer.pause()
        return settled(pilot)

    assert snap_compare(Tab(TABS[name]), terminal_size=SIZE, run_before=shown)


async def test_the_quit_question_says_one_process_in_the_singular():
    from textual.widgets import Static

    app = Over(lambda: QuitScreen(["talker-1"]))
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        said = str(app.screen.query(Static).first().render())
        assert said.startswith("1 process still runs: talker-1\nStop it and quit?"), said
