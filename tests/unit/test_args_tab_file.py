"""The Args tab and the start's notices, as the TUI says them of the session it follows: a
launch file saved while the tab shows, an argument the file does not declare, a value
unlike its default's type. All of it is the client's reading of the file and the values
(the server only runs what is applied), so an in-memory session stands for the server;
tests/integration keeps what a real session does with them (test_relaunch: F5 applies the
edited file, the server refuses a broken one; the headless and --print warnings).
"""

from __future__ import annotations

from pathlib import Path

from textual.widgets import Static

from tests.unit.pilot_sessions import launch_file, shown
from tests.unit.test_app_pilot import until
from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.output_store import View

EDITABLE = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('word', 'alpha')
    sl.add_action(ExecuteProcess(name='echo', cmd=[
        'sh', '-c', 'echo {said} "$0"; exec sleep 600', sl.arg('word')]))
    return sl.launch_description()
"""

TYPO = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('robot', 'r1')
    with sl.group(ns=sl.arg('robot')):
        sl.add_action(ExecuteProcess(name='say', cmd=['sh', '-c', 'echo in "$0"; exec sleep 600',
                                                      sl.arg('robot')]))
    return sl.launch_description()
"""

TYPED = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('gain', 1.5)
    sl.declare_arg('count', 3)
    sl.add_action(ExecuteProcess(name='uses', cmd=['sh', '-c', 'echo gain "$0"; exec sleep 600',
                                                   sl.arg('gain')]))
    return sl.launch_description()
"""
GAIN_NOTE = "argument 'gain' = 'abc' is not a number like its default 1.5 (passed as written)"


def preview_text(app: TuiLaunchApp) -> str:
    return str(app.query_one("#args-preview", Static).render())


def header(app: TuiLaunchApp) -> str:
    return str(app.query_one("#status", Static).render())


def notices(app: TuiLaunchApp) -> list[str]:
    return [n.message for n in app._notifications]


async def test_the_args_tab_follows_the_file_saved_while_it_shows(tmp_path: Path) -> None:
    """The operator keeps the Args tab open beside an editor: each save is previewed with
    no key pressed, so the tab never says "no longer loads" about a file fixed since, nor
    "No change" about one edited since."""
    path = launch_file(tmp_path, EDITABLE.format(said="word"), "test_launch.py")
    async with shown(tmp_path, path, name="test_launch-1", size=(120, 36)) as (
            app, pilot, memory):
        await pilot.press("2")
        path.write_text(EDITABLE.format(said="word").replace(
            "return sl.launch_description()", "return sl.launch_description("))
        await until(pilot, lambda: "no longer loads" in preview_text(app), "the broken file")
        path.write_text(EDITABLE.format(said="said"))
        await until(pilot, lambda: "changed on disk: changes: echo-1" in preview_text(app),
                    "the fixed file's change")
        assert not app.query_one("#args-preview").has_class("error")
        path.write_text(EDITABLE.format(said="word"))
        await until(pilot, lambda: "changed on disk: no process changes" in preview_text(app),
                    "the file as it runs")
        # said once (it read "no process changes. No process changes; F5 applies ...")
        assert preview_text(app) == f"{path.name} changed on disk: no process changes; F5 " \
            "applies it anyway."
        # a default edited: the form still shows the running one, the preview says both
        path.write_text(EDITABLE.format(said="word").replace("'alpha'", "'gamma'"))
        await until(pilot, lambda: "changed on disk: word's default alpha -> gamma; "
                    "changes: echo-1" in preview_text(app), "the default's edit")
        assert "apply" not in memory.ops()  # nothing was applied meanwhile


async def test_a_mistyped_argument_is_said_in_the_tui_and_not_shown_as_applied(
        tmp_path: Path) -> None:
    path = launch_file(tmp_path, TYPO, "test_launch.py")
    # the TUI of `tuilaunch FILE robto:=r2`: the operator who typed it is told
    async with shown(tmp_path, path, {"robto": "r2"}, name="test_launch-1",
                     size=(120, 36), owner=True) as (app, pilot, _):
        await until(pilot, lambda: "say-1" in app.launch_tree.rows, "the tree")
        said = notices(app)
        assert any("argument 'robto' is not declared by test_launch.py or its includes; "
                   "did you mean 'robot'?" in message for message in said), said
        # the header lists what applies, and the typo apart, never as applied
        await until(pilot, lambda: "not declared: robto" in header(app), "the header's note")
        assert "robto:=r2" not in header(app)
        # the all nodes pane keeps it after the toast is gone
        await pilot.press("a")
        await until(pilot, lambda: any("did you mean 'robot'?" in line
                                       for line in app.output_panel.pane_lines()),
                    "the note in the all nodes pane")
        lines = [line.text for line in app.store.lines(View("launch"))]
        assert any("did you mean 'robot'?" in line for line in lines), lines


async def test_a_value_unlike_its_defaults_type_is_warned_at_start_and_in_the_args_tab(
        tmp_path: Path) -> None:
    path = launch_file(tmp_path, TYPED, "test_launch.py")
    async with shown(tmp_path, path, {"gain": "abc"}, name="test_launch-1",
                     size=(120, 36), owner=True) as (app, pilot, _):
        await until(pilot, lambda: "uses-1" in app.launch_tree.rows, "the tree")
        said = notices(app)
        assert any(GAIN_NOTE in message for message in said), said
        await pilot.press("2")  # nothing edited: the Args tab says it all the same
        await until(pilot, lambda: f"Warning: {GAIN_NOTE}" in preview_text(app),
                    "the warning in the Args tab")
