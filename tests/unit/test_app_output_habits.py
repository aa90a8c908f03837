"""The output pane's habits and a group's stop as the detail line says it, over an in-memory
session (moved from tests/integration/test_output_panes.py, which keeps what real processes
print: tabs, floods, prompts, long lines): an empty result says which key undoes it, a
search hides nothing, a group whose nodes take their time to stop says they are stopping."""

from __future__ import annotations

from pathlib import Path

from tests.unit.pilot_sessions import launch_file, pane_status, rows, shown, toasts
from tests.unit.test_app_pilot import detail, select, until
from tuilaunch.engine.run.events import ExitCause, Output, ProcessExited, Stopping
from tuilaunch.tui.screens.dialogs import ConfirmScreen

TABLE = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='tab_printer', cmd=['tab_printer'])])
"""

PRINTED = ["PID\tTTY\tTIME\tCMD", "1\tpts/0\t00:00:01\tbash", "ab\tcd\tend"]
"""What tab_printer prints (tests/integration/programs), in part."""


async def test_an_empty_filter_says_so_and_esc_shows_all_again(tmp_path: Path) -> None:
    async with shown(tmp_path, launch_file(tmp_path, TABLE)) as (app, pilot, port):
        select(app, "tab_printer-1")
        port.tell(Output("tab_printer-1", stream="stdout", lines=PRINTED))
        await until(pilot, lambda: any("end" in r for r in rows(app)), "its lines")
        await pilot.press("backslash", *"zzz", "enter")
        await until(pilot, lambda: rows(app)[:1] == ["no line matches 'zzz' (esc: show all)"],
                    "the empty filter said")
        assert "only 'zzz'" in pane_status(app)
        await pilot.press("escape")
        await until(pilot, lambda: any("PID" in r for r in rows(app)), "every line again")
        assert "only" not in pane_status(app)
        # the level filter says its own word; a search that finds nothing says so too
        await pilot.press("l", "l", "l")
        await until(pilot, lambda: rows(app)[:1] == ["no line at ERROR or above (l: next "
                                                     "level)"], "the empty level said")
        await pilot.press("l", "l")
        await until(pilot, lambda: any("PID" in r for r in rows(app)), "every level again")
        await pilot.press("slash", *"qqq", "enter")
        await until(pilot, lambda: "/qqq no line matches" in pane_status(app), "no match")
        assert any("no line matches 'qqq'" in t for t in toasts(app))
        assert any("PID" in r for r in rows(app))  # a search hides nothing


STUBBORN = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name=name, cmd=['stubborn'], sigterm_timeout='600')
        for name in ('left', 'right')])
"""


async def test_a_group_being_stopped_says_its_nodes_are_stopping(tmp_path: Path) -> None:
    async with shown(tmp_path, launch_file(tmp_path, STUBBORN)) as (app, pilot, port):
        tree = app.launch_tree
        tree.move_cursor(tree.root)
        await until(pilot, lambda: "2 of 2 processes running" in detail(app), "the root")
        await pilot.press("s")
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "the question")
        await pilot.press("y")
        await until(pilot, lambda: {f["process"] for op, f in port.asked if op == "stop"}
                    == {"left-1", "right-2"}, "both stops asked")
        # they ignore SIGINT: the stop lasts, and the row says so rather than "0 running"
        port.tell(Stopping("left-1", pid=1000), Stopping("right-2", pid=1001))
        await until(pilot, lambda: "0 of 2 processes running, 2 stopping" in detail(app),
                    "2 stopping said")
        port.tell(*(ProcessExited(process, pid=pid, code=-15, reason="killed by SIGTERM",
                                  cause=ExitCause.ASKED)
                    for process, pid in (("left-1", 1000), ("right-2", 1001))))
        await until(pilot, lambda: "0 of 2 processes running" in detail(app)
                    and "stopping" not in detail(app), "stopped")
