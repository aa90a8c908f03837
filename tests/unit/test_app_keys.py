"""The Nodes tab's keys over an in-memory session (memory_port.py): which the footer offers
on a node, a group and a lifecycle node; `c`, `L`, `o`, `?`, the command palette, and the
lifecycle steps `]` `[`, each by what it shows and what it asks of the session."""

from __future__ import annotations

import textwrap
from pathlib import Path

from textual.command import CommandList, CommandPalette
from textual.widgets import Static
from textual.widgets._footer import FooterKey

from tests.unit.test_app_pilot import (
    following,
    footer,
    row,
    select,
    status,
    toasts,
    until,
)
from tuilaunch.engine.run.events import ExitCause, LifecycleChanged, Output, ProcessExited
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.screens.dialogs import ChoiceScreen, ConfirmScreen, HelpScreen
from tuilaunch.tui.screens.interact_dialogs import CommandScreen

LIFECYCLE = """
from launch import LaunchDescription
from launch_ros.actions import LifecycleNode, Node

def generate_launch_description():
    return LaunchDescription([
        LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker', name='lc',
                      namespace=''),
        Node(package='tuilaunch_demos', executable='listener', name='plain'),
    ])
"""


def texts(app: TuiLaunchApp) -> list[str]:
    """The texts on the screen on top (a dialog's)."""
    return [str(w.render()) for w in app.screen.query(Static)]


async def test_the_footer_offers_stop_and_restart_of_a_running_node(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        select(app, "talker-1")
        await until(pilot, lambda: footer(app).get("Stop") is True, "Stop offered")
        keys = footer(app)
        assert keys["Restart"] is True
        assert keys["Start"] is False  # greyed: it runs
        assert "Lifecycle up" not in keys  # not a lifecycle node: not offered at all
        port.tell(ProcessExited("talker-1", pid=1000, code=0, reason="exit code 0"))
        await until(pilot, lambda: footer(app).get("Start") is True, "Start once it ended")
        assert footer(app)["Stop"] is False


async def test_a_row_selected_greys_or_offers_the_footers_keys_where_they_are(
        tmp_path: Path) -> None:
    """The same keys, only some greyed or offered: the footer's keys stay, not drawn anew
    (a FooterKey acts on the press: one pressed while the footer was being drawn anew went
    to a key already removed, and a tap on Stop right after a tap on a row was lost)."""
    async with following(tmp_path) as (app, pilot, port):
        select(app, "ns /r1/control")
        await until(pilot, lambda: footer(app).get("Type") is False, "Type greyed on a group")
        await pilot.pause()  # the redraws the first bindings asked for, done
        drawn = list(app.screen.query(FooterKey))
        select(app, "talker-1")
        await until(pilot, lambda: footer(app).get("Type") is True, "Type offered on a node")
        port.tell(ProcessExited("talker-1", pid=1000, code=0, reason="exit code 0"))
        await until(pilot, lambda: footer(app).get("Start") is True, "Start once it ended")
        assert footer(app)["Stop"] is False
        assert list(app.screen.query(FooterKey)) == drawn
        assert all(key.is_attached for key in drawn)


async def test_a_groups_footer_offers_its_commands_and_only_the_tabs_own_keys(
        tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, _port):
        select(app, "ns /r1/control")
        await until(pilot, lambda: footer(app).get("Stop") is True, "Stop offered")
        assert footer(app)["Restart"] is True
        await pilot.press("2")  # the Args tab: the selection's commands are not its keys
        # the footer is drawn anew for the tab: empty for a moment, so both are waited for
        await until(pilot, lambda: "Apply" in footer(app) and "Stop" not in footer(app),
                    "Apply and no Stop on the Args tab")


async def test_c_shows_the_command_line_the_session_says(tmp_path: Path) -> None:
    command = "cd /tmp && env -- A=1 /opt/talker --ros-args -r __ns:=/r1"
    async with following(tmp_path) as (app, pilot, port):
        port.answers["status"] = lambda **_: {"processes": [
            {"id": "talker-1", "command_line": command, "terminal": False}]}
        select(app, "talker-1")
        await pilot.press("c")
        await until(pilot, lambda: isinstance(app.screen, CommandScreen), "the dialog")
        assert texts(app)[:2] == ["talker-1 was started with (y copies it, esc closes):",
                                  command]
        await pilot.press("escape")
        await until(pilot, lambda: not isinstance(app.screen, CommandScreen), "closed")


async def test_c_on_a_process_without_a_command_line_says_so(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.answers["status"] = lambda **_: {"processes": []}
        select(app, "talker-1")
        await pilot.press("c")
        await until(pilot, lambda: "talker-1 has no command line (it could not be "
                    "resolved)" in toasts(app), "one line saying why")
        assert not isinstance(app.screen, CommandScreen)


async def test_capital_l_sets_a_nodes_log_level_by_the_name_it_reports(
        tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        select(app, "talker-1")
        # its node is named by its code: the name comes from its log lines
        port.tell(Output("talker-1", stream="stderr",
                         lines=["[INFO] [1700000000.1] [r1.talker]: Publishing: hi"]))
        await until(pilot, lambda: "/r1/talker" in str(app.detail_bar.render()),
                    "the name it reports")
        await pilot.press("L")
        await until(pilot, lambda: isinstance(app.screen, ChoiceScreen), "the levels")
        assert "Log level of /r1/talker (talker-1):" in texts(app)
        await pilot.press("down", "down", "enter")  # info -> warn -> error
        await until(pilot, lambda: "log_level" in port.ops(), "the level asked")
        assert dict(port.asked)["log_level"] == {"node": "/r1/talker", "level": "error"}
        await until(pilot, lambda: "/r1/talker: log level error" in toasts(app), "said")


async def test_a_node_without_a_logger_service_is_offered_a_restart(tmp_path: Path) -> None:
    def refuse(**_: object) -> None:
        raise SessionError("session bringup: /r1/talker has no logger service")

    async with following(tmp_path) as (app, pilot, port):
        port.answers["log_level"] = refuse
        select(app, "talker-1")
        await pilot.press("L")
        await until(pilot, lambda: isinstance(app.screen, ChoiceScreen), "the levels")
        await pilot.press("up", "enter")  # info -> debug
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "the offer")
        assert any("Restart talker-1 with --log-level debug?" in t for t in texts(app))
        await pilot.press("y")
        await until(pilot, lambda: "restart" in port.ops(), "the restart asked")
        assert dict(port.asked)["restart"] == {"process": "talker-1", "log_level": "debug"}


async def test_o_lists_the_selected_nodes_topics(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.answers["topics"] = lambda **fields: {"topics": [
            {"name": "/r1/chatter", "types": ["std_msgs/msg/String"], "publishers": [],
             "subscribers": []}] if fields.get("node") else []}
        select(app, "talker-1")
        port.tell(Output("talker-1", stream="stderr",
                         lines=["[INFO] [1700000000.1] [r1.talker]: Publishing: hi"]))
        await until(pilot, lambda: "/r1/talker" in str(app.detail_bar.render()), "named")
        await pilot.press("o")
        await until(pilot, lambda: app.tabs.active == "topics", "the Topics tab")
        scope = app.topics_panel.query_one("#tpc-scope", Static)
        await until(pilot, lambda: str(scope.render()) == "node /r1/talker (x: all)",
                    "the node's topics")
        # the scope is said first, the listing asked after it: its answer is what shows
        await until(pilot, lambda: "/r1/chatter" in app.topics_panel.entries, "its topic")
        assert ("topics", {"node": "/r1/talker"}) in port.asked


async def test_a_group_has_no_log_level_nor_topics_of_a_node(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        select(app, "ns /r1")
        await until(pilot, lambda: str(app.detail_bar.render()).startswith("ns /r1:"),
                    "the group selected")
        await pilot.press("L", "o")
        await pilot.pause(0.1)
        assert app.tabs.active == "nodes"
        assert not isinstance(app.screen, ChoiceScreen)
        assert "log_level" not in port.ops()


async def test_question_mark_shows_the_keys_and_escape_closes_them(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, _port):
        await pilot.press("question_mark")
        await until(pilot, lambda: isinstance(app.screen, HelpScreen), "the keys")
        shown = "\n".join(texts(app))
        assert "1-5  tabs: Nodes Args Services Params Topics" in shown
        assert "F5   apply edited arguments" in shown
        await pilot.press("escape")
        await until(pilot, lambda: not isinstance(app.screen, HelpScreen), "closed")
        assert app.focused is app.launch_tree


async def test_the_palette_offers_the_selections_commands_and_the_tabs(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, _port):
        select(app, "talker-1")
        await pilot.pause()
        titles = [c.title for c in app.get_system_commands(app.screen)]
        for title in ("Keys", "Stop selected", "Restart selected", "Start selected",
                      "Apply arguments", "Detach", "Topics of selected node",
                      "Log level of selected node", "Open Nodes", "Open Arguments",
                      "Open Topics"):
            assert title in titles, title
        assert not any(t.startswith("Lifecycle") for t in titles)  # not a lifecycle node
        select(app, "ns /r1")
        await pilot.pause()
        titles = [c.title for c in app.get_system_commands(app.screen)]
        assert "Stop selected" in titles and "Topics of selected node" not in titles


async def test_colon_then_a_word_lists_the_palettes_matches(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        select(app, "talker-1")
        await pilot.press("colon", *"stop")
        await until(pilot, lambda: isinstance(app.screen, CommandPalette), "the palette")
        options = app.screen.query_one(CommandList)
        await until(pilot, lambda: [str(o.prompt).split("\n")[0] for o in options._options]
                    == ["Stop selected"], "its one match")
        assert "stop" not in port.ops()  # the letters went to the palette, not to `s`
        await pilot.press("enter")
        await until(pilot, lambda: ("stop", {"process": "talker-1"}) in port.asked,
                    "the stop asked from the palette")


async def test_lifecycle_keys_step_a_lifecycle_node_and_follow_its_state(
        tmp_path: Path) -> None:
    launch = tmp_path / "lc_launch.py"
    launch.write_text(textwrap.dedent(LIFECYCLE))
    async with following(tmp_path, launch, name="lc") as (app, pilot, port):
        select(app, "lc-1")
        port.tell(LifecycleChanged("lc-1", reason="unconfigured"))
        await until(pilot, lambda: row(app, "lc-1").endswith("· unconfigured"),
                    "its lifecycle state on the row")
        await until(pilot, lambda: footer(app).get("Lifecycle up") is True, "] offered")
        assert footer(app)["Lifecycle down"] is False  # nothing below unconfigured
        await pilot.press("right_square_bracket", "right_square_bracket")
        # the second step is taken from where the first leads, after it
        await until(pilot, lambda: port.ops().count("transition") == 2, "two steps asked")
        assert [f["transition"] for op, f in port.asked if op == "transition"] == \
            ["configure", "activate"]
        port.tell(LifecycleChanged("lc-1", reason="inactive"),
                  LifecycleChanged("lc-1", reason="active"))
        await until(pilot, lambda: row(app, "lc-1").endswith("· active"), "active")
        assert "lifecycle state active" in str(app.detail_bar.render())
        await until(pilot, lambda: footer(app).get("Lifecycle down") is True, "[ offered")
        await pilot.press("left_square_bracket")
        await until(pilot, lambda: port.ops().count("transition") == 3, "a step down")
        assert port.asked[-1] == ("transition", {"process": "lc-1",
                                                 "transition": "deactivate"})


async def test_lifecycle_keys_are_not_offered_on_a_plain_node(tmp_path: Path) -> None:
    launch = tmp_path / "lc_launch.py"
    launch.write_text(textwrap.dedent(LIFECYCLE))
    async with following(tmp_path, launch, name="lc") as (app, pilot, port):
        port.tell(LifecycleChanged("lc-1", reason="active"))
        await until(pilot, lambda: row(app, "lc-1").endswith("· active"), "lc-1 active")
        select(app, "plain-2")
        await until(pilot, lambda: footer(app).get("Stop") is True, "plain-2's keys")
        assert "Lifecycle up" not in footer(app) and "Lifecycle down" not in footer(app)
        await pilot.press("right_square_bracket", "left_square_bracket")
        await pilot.pause(0.1)
        assert "transition" not in port.ops()
        select(app, "lc-1")
        await pilot.pause()
        titles = [c.title for c in app.get_system_commands(app.screen)]
        assert "Lifecycle: deactivate lc-1" in titles
        assert status(app).startswith("[lc] lc_launch.py  2 running")


async def test_a_failed_nodes_restart_is_asked_of_the_session(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.tell(ProcessExited("monitor-5", pid=1004, code=1, reason="exit code 1",
                                cause=ExitCause.CRASHED))
        select(app, "monitor-5")
        await until(pilot, lambda: footer(app).get("Start") is True, "Start offered")
        await pilot.press("r")
        await until(pilot, lambda: ("restart", {"process": "monitor-5"}) in port.asked,
                    "the restart asked")
