"""The TUI over long sessions, its own side (moved from tests/integration/
test_tui_long_sessions.py; what needs a real terminal, a flood or a node stays there): panes
keep the newest lines past their scrollback and repaint only on a change, keys in one read
are applied in order, values the plan cannot use are refused, 80x24 stays readable, process
events read as ros2 launch prints them, follow holds, the tab keys work from everywhere."""

from __future__ import annotations

import re
import time
from pathlib import Path

import pytest
from textual.widgets import Static

from tests.unit.pilot_sessions import (
    burst,
    keys_handled,
    launch_file,
    line_view,
    pane_status,
    rows,
    shown,
    toasts,
)
from tests.unit.test_app_pilot import detail, row, until
from tuilaunch.engine.run.events import (
    ActionFinished,
    ExitCause,
    Failed,
    Output,
    ProcessExited,
    Started,
    Stopping,
)
from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.dialogs import ConfirmScreen
from tuilaunch.tui.screens.fields import Field
from tuilaunch.tui.screens.tree_panel import LaunchTree

COUNTER = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='counter0', cmd=['counter'])])
"""

QUIET = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='quiet', cmd=['sleep', '600'])])
"""


def counted(first: int, last: int) -> Output:
    """The counter's lines `first` to `last - 1`, as its ROS logger prints them."""
    return Output("counter0-1", stream="stdout", lines=[
        f"[INFO] [{1700000000 + i / 1000:.3f}] [counter]: line {i}" for i in range(first, last)])


def said(robot: str, first: int, last: int) -> Output:
    """The talker's lines, as it prints them on stderr."""
    return Output("talker-1", stream="stderr", lines=[
        f'[INFO] [{1700000000 + i / 10:.1f}] [{robot}.talker]: Publishing: "{robot} says hi: '
        f'{i}"' for i in range(first, last)])


def last_number(app: TuiLaunchApp) -> int:
    """The line number on the pane's bottom row, as a user reads it."""
    rows = [r for r in line_view(app).visible_text() if "line " in r]
    return int(rows[-1].rsplit("line ", 1)[1]) if rows else -1


# --- 1. the pane never freezes ---------------------------------------------------------


async def test_soak_a_small_scrollback_keeps_showing_the_newest_lines(tmp_path: Path) -> None:
    """scrollback 100 and 1500 lines: the pane shows the newest line each time more came,
    not the 100th."""
    async with shown(tmp_path, launch_file(tmp_path, COUNTER), scrollback=100) \
            as (app, pilot, port):
        await pilot.press("down", "down")  # the counter's own pane
        assert app.output_panel.view.process == "counter0-1"
        for first in (0, 500, 1000):
            port.tell(counted(first, first + 500))
            await until(pilot, lambda first=first: last_number(app) == first + 499,
                        f"line {first + 499} at the bottom")
        assert len(line_view(app).lines) == 100
        assert line_view(app).following


async def test_a_search_past_the_scrollback_says_where_the_older_lines_are(
        tmp_path: Path) -> None:
    """A search for a line the pane no longer holds does not just say "no line matches":
    it says how many lines the pane keeps and that the log files have them all."""
    async with shown(tmp_path, launch_file(tmp_path, COUNTER), scrollback=100) \
            as (app, pilot, port):
        await pilot.press("down", "down")
        port.tell(counted(0, 300))
        await until(pilot, lambda: last_number(app) == 299, "line 299 at the bottom")
        assert len(line_view(app).lines) == 100  # lines 200 to 299
        app.output_panel.set_search("line 3")  # lines 3 and 30-39: only in the log file now
        await until(pilot, lambda: any(t.startswith(
            "no line matches 'line 3' in the 100 lines this pane keeps; every line is in "
            "the log files") for t in toasts(app)), "where the older lines are")


async def test_the_pane_repaints_only_when_its_lines_change(tmp_path: Path,
                                                            monkeypatch) -> None:
    async with shown(tmp_path, launch_file(tmp_path, COUNTER)) as (app, pilot, port):
        await pilot.press("down", "down")
        port.tell(counted(0, 3))
        await until(pilot, lambda: last_number(app) == 2, "the three lines")
        view = line_view(app)
        open_ticks: list[float] = []
        flush = view.flush

        def counting(now: float | None = None) -> bool:
            # a tick at which the pane would repaint, had anything changed
            if time.monotonic() - view._painted_at >= 1 / view.max_fps:
                open_ticks.append(time.monotonic())
            return flush(now)

        monkeypatch.setattr(view, "flush", counting)
        before = view.repaints
        await until(pilot, lambda: len(open_ticks) >= 3, "three ticks free to repaint")
        assert view.repaints == before  # nothing new: nothing drawn
        port.tell(counted(3, 4))
        await until(pilot, lambda: last_number(app) == 3, "a new line drawn")
        assert view.repaints > before


# --- 3. keys that arrive together --------------------------------------------------------


async def test_keys_in_one_read_are_applied_in_order_and_f5_applies_what_was_typed(
        tmp_path: Path) -> None:
    arguments = {"robot": "tuik", "services": "false", "listener": "false"}
    async with shown(tmp_path, arguments=arguments) as (app, pilot, port):
        await pilot.press("2")
        field = app.query_one("#arg-rate", Field)
        field.focus()
        await pilot.pause()
        # 26 backspace+letter pairs in one read: every letter replaces the one before
        burst(app, "end", *[k for letter in "abcdefghijklmnopqrstuvwxyz"
                            for k in ("backspace", letter)])
        await until(pilot, lambda: field.value == "2.z", "2.z in the field")
        # ctrl+u, 3, F5 in one read: the node gets rate 3, not an empty value
        burst(app, "ctrl+u", "3", "f5")
        await until(pilot, lambda: "apply" in port.ops(), "the relaunch asked")
        assert dict(port.asked)["apply"]["arguments"]["rate"] == "3"
        await until(pilot, lambda: app.session.arguments.get("rate") == "3", "rate:=3")


# --- 4. values the plan cannot use -------------------------------------------------------


async def test_the_preview_refuses_bad_names_and_f5_applies_nothing(tmp_path: Path) -> None:
    async with shown(tmp_path, arguments={"robot": "tuin", "services": "false"}) \
            as (app, pilot, port):
        await pilot.press("2")
        preview = app.query_one("#args-preview", Static)
        for value, why in (("bad ns!", "namespace '/bad ns!'"),
                           ("9lives", "namespace '/9lives'")):
            field = app.query_one("#arg-robot", Field)
            field.value = value
            await until(pilot, lambda why=why: preview.has_class("error")
                        and why in str(preview.render()), f"{value!r} refused")
            said = len(toasts(app))
            await pilot.press("f5")
            await until(pilot, lambda said=said: any(
                "cannot apply" in t for t in toasts(app)[said:]), "F5 saying it cannot")
            assert "apply" not in port.ops()
            assert app.session.arguments == {"robot": "tuin", "services": "false"}
            field.value = "tuin"
            await until(pilot, lambda: not preview.has_class("error"), "the name back")


INT_ARGUMENT = """
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('copies', 1, description='how many')
    sl.node('tuilaunch_demos', 'talker', name='t')
    return sl.launch_description()
"""


async def test_an_int_field_warns_of_a_fraction_and_applies_it_as_ros2_launch_would(
        tmp_path: Path) -> None:
    async with shown(tmp_path, launch_file(tmp_path, INT_ARGUMENT)) as (app, pilot, port):
        await pilot.press("2")
        field = app.query_one("#arg-copies", Field)
        field.focus()
        await pilot.press("end", "backspace", *"1.5")
        assert field.value == "1.5"  # not 15: the point is kept
        preview = app.query_one("#args-preview", Static)
        await until(pilot, lambda: "Warning: argument 'copies' = '1.5' is not a whole "
                    "number like its default 1" in str(preview.render()), "the warning")
        assert not preview.has_class("error")
        await pilot.press("f5")  # launch arguments are strings: ros2 launch takes copies:=1.5
        await until(pilot, lambda: app.session.arguments.get("copies") == "1.5", "applied")
        assert dict(port.asked)["apply"]["arguments"] == {"copies": "1.5"}


# --- 5. readable at 80x24 ------------------------------------------------------------------


async def test_at_80x24_the_message_is_on_screen_and_the_split_adapts(tmp_path: Path) -> None:
    async with shown(tmp_path, arguments={"robot": "tuiw", "services": "false"}) \
            as (app, pilot, port):
        tree = app.query_one(LaunchTree)
        assert 22 <= tree.outer_size.width <= 30
        await pilot.press("down", "down", "down")
        assert app.output_panel.view.process == "talker-1"
        port.tell(said("tuiw", 0, 5))
        await until(pilot, lambda: any(r.startswith('I Publishing: "tuiw says hi')
                                       for r in line_view(app).visible_text()),
                    "the message from its first column")
        width = tree.outer_size.width
        await pilot.press("greater_than_sign")
        await until(pilot, lambda: tree.outer_size.width == width + 4, "4 columns wider")
        await pilot.press("less_than_sign", "less_than_sign")
        await until(pilot, lambda: tree.outer_size.width == width - 4, "4 narrower")
        # timestamps on a toggle, the full line as printed on another
        await pilot.press("T")
        await until(pilot, lambda: re.match(r"\d\d:\d\d:\d\d\.\d{3} I Publishing",
                                            rows(app)[-1]), "the time")
        await pilot.press("T", "f")
        await until(pilot, lambda: rows(app)[-1].startswith("[INFO] ["), "the line as printed")


async def test_the_split_is_wider_on_a_wider_terminal(tmp_path: Path) -> None:
    async with shown(tmp_path, launch_file(tmp_path, QUIET), size=(120, 40)) \
            as (app, pilot, _port):
        await until(pilot, lambda: app.query_one(LaunchTree).outer_size.width == 42,
                    "a 42-column tree")


async def test_wrap_shows_a_long_line_whole(tmp_path: Path) -> None:
    async with shown(tmp_path, launch_file(tmp_path, QUIET)) as (app, pilot, port):
        await pilot.press("down", "down")
        port.tell(Output("quiet-1", stream="stdout", lines=["start-" + "x" * 150 + "-end"]))
        view = line_view(app)
        await until(pilot, lambda: any("start-" in r for r in view.visible_text()), "shown")
        assert not any("-end" in r for r in view.visible_text())
        await pilot.press("z")
        await until(pilot, lambda: any("-end" in r for r in view.visible_text()), "whole")
        assert "wrap" in pane_status(app)


# --- 6. process events in the panes ---------------------------------------------------------

THREE = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='crash', cmd=['sh', '-c', 'sleep 0.2; exit 3']),
        ExecuteProcess(name='absent', cmd=['no-such-command-tui']),
        ExecuteProcess(name='fine', cmd=['sleep', '600'])])
"""


async def test_a_failed_nodes_pane_says_how_it_died_and_its_reason_is_on_screen(
        tmp_path: Path) -> None:
    async with shown(tmp_path, launch_file(tmp_path, THREE), started=False) \
            as (app, pilot, port):
        absent = app.session.plan.process("absent-2").error
        assert absent is not None and "not found" in absent
        port.tell(Started("crash-1", pid=2001), Failed("absent-2", reason=absent),
                  Started("fine-3", pid=2003))
        port.tell(ProcessExited("crash-1", pid=2001, code=3, reason="exit code 3",
                                cause=ExitCause.CRASHED))
        await until(pilot, lambda: "failed" in row(app, "crash-1"), "crash-1 failed")
        crash = app.store.text(View("crash-1"))
        assert "process started with pid [2001]" in crash
        assert "process has died [pid 2001, exit code 3]" in crash
        assert any("[crash-1] process has died" in line for line in app.store.text(View()))
        await pilot.press("down", "down")  # all nodes, then the crash
        assert app.output_panel.view.process == "crash-1"
        await until(pilot, lambda: any("process has died" in r
                                       for r in line_view(app).visible_text()), "on screen")
        assert "failed" in detail(app) and "exit code 3" in detail(app)
        await pilot.press("down")
        await until(pilot, lambda: "not found" in detail(app), "absent-2's reason")
        assert any("failed:" in line for line in app.store.text(View("absent-2")))
        await pilot.press("down", "s")  # the operator stops `fine`: a stop, not a death
        await until(pilot, lambda: ("stop", {"process": "fine-3"}) in port.asked, "asked")
        port.tell(Stopping("fine-3", pid=2003),
                  ProcessExited("fine-3", pid=2003, code=-2, reason="killed by SIGINT",
                                cause=ExitCause.ASKED))
        await until(pilot, lambda: "process stopped [pid 2003, killed by SIGINT]"
                    in app.store.text(View("fine-3")), "its stop said")
        assert not any("process has died" in line for line in app.store.text(View("fine-3")))
        await until(pilot, lambda: "exited" in row(app, "fine-3"), "fine-3 exited")
        assert "failed" not in row(app, "fine-3")


async def test_action_rows_never_read_pid_none(tmp_path: Path) -> None:
    async with shown(tmp_path, arguments={"robot": "tuia", "listener": "false"}) \
            as (app, pilot, port):
        port.tell(ActionFinished("set_parameters-1", reason="done"))
        await until(pilot, lambda: "done" in row(app, "set_parameters-1"), "done")
        assert "pid None" not in row(app, "set_parameters-1")


# --- 7. tab keys from fields --------------------------------------------------------------


async def test_escape_leaves_any_field_and_digits_then_switch_tabs(tmp_path: Path) -> None:
    async with shown(tmp_path, arguments={"robot": "tuit", "services": "false"}) \
            as (app, pilot, _port):
        await pilot.press("2")
        field = app.query_one("#arg-rate", Field)
        field.focus()
        await pilot.pause()
        burst(app, "end", "1")
        await until(pilot, lambda: field.value == "2.01", "the digit typed")
        assert app.tabs.active == "args"  # a digit is typed
        field.value = "2.0"
        burst(app, "escape", "3")
        await until(pilot, lambda: app.tabs.active == "services", "the Services tab")
        assert field.value == "2.0"
        # the tab shows its list, not a text field: the tab keys and q work at once
        await until(pilot, lambda: app.focused is app.query_one("#svc-list"), "its list")
        burst(app, "escape", "4")
        await until(pilot, lambda: app.tabs.active == "params", "the Params tab")
        burst(app, "escape", "1")
        await until(pilot, lambda: app.tabs.active == "nodes", "the Nodes tab")
        assert isinstance(app.focused, LaunchTree), app.focused
        await pilot.press("slash", *"abc")
        burst(app, "escape", "2")
        await until(pilot, lambda: app.tabs.active == "args", "the Args tab")
        assert app.output_panel.search == ""


# --- 8. follow ----------------------------------------------------------------------------


async def test_follow_holds_across_node_switches_resizes_and_a_cancelled_search(
        tmp_path: Path) -> None:
    async with shown(tmp_path, arguments={"robot": "tuif", "services": "false"}) \
            as (app, pilot, port):
        panel = app.output_panel
        view = line_view(app)
        told = 0

        async def more_at_newest(count: int = 1) -> None:
            """Lines come: the pane shows the newest at its bottom row."""
            nonlocal told
            port.tell(said("tuif", told, told + count))
            told += count
            await until(pilot, lambda: view.visible_text()[-1].endswith(
                f'"tuif says hi: {told - 1}"'), f"line {told - 1} at the bottom")

        await more_at_newest(50)
        await pilot.press("down", "down", "down")  # talker
        assert view.following and panel.unseen == 0
        await more_at_newest()
        await pilot.press("up", "up")  # all nodes
        assert view.following and panel.unseen == 0
        await more_at_newest()
        await pilot.press("slash", "escape")
        assert view.following
        await pilot.resize_terminal(100, 30)
        await more_at_newest()
        assert view.following and panel.unseen == 0
        # scrolled up: what arrives below is counted, the view holds
        view.focus()
        await pilot.press("pageup")
        assert not view.following
        unseen = panel.unseen
        port.tell(said("tuif", told, told + 3))
        await until(pilot, lambda: panel.unseen == unseen + 3, "3 more lines below")
        await pilot.press("G")
        assert view.following and panel.unseen == 0


# --- 9. a root stop asks ---------------------------------------------------------------------


async def test_stop_on_the_root_asks_first(tmp_path: Path) -> None:
    async with shown(tmp_path, arguments={"robot": "tuis", "services": "false"}) \
            as (app, pilot, port):
        app.query_one(LaunchTree).focus()
        await pilot.press("home")  # the root row
        await pilot.press("s")
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "the question")
        await pilot.press("n")
        await until(pilot, lambda: not isinstance(app.screen, ConfirmScreen), "answered")
        await keys_handled(pilot, app)
        assert "stop" not in port.ops()
        await pilot.press("s", "y")
        running = {p.id for p in app.session.plan.enabled_processes()}
        await until(pilot, lambda: {f["process"] for op, f in port.asked if op == "stop"}
                    == running, "a stop of every running process asked")


# --- 12. smaller things -----------------------------------------------------------------------


async def test_descriptions_keep_brackets_and_the_current_match_stands_out(
        tmp_path: Path) -> None:
    async with shown(tmp_path, arguments={"robot": "tuim", "services": "false",
                                          "rate": "20"}) as (app, pilot, port):
        await pilot.press("2")
        helps = [str(s.render()) for s in app.query(".arg-help")]
        assert any("talker publishing rate [Hz]" in h for h in helps)
        await pilot.press("escape", "1")
        port.tell(said("tuim", 0, 12))
        await until(pilot, lambda: len(app.store.lines(View("talker-1"))) > 10, "lines")
        await pilot.press("down", "down", "down", "slash", *"says", "enter")
        view = line_view(app)
        await until(pilot, lambda: view.current_match is not None, "a current match")
        assert view.current_match is not None
        current = view._text(view.current_match)
        other = view._text(view.matches()[0] if view.matches()[0] != view.current_match
                           else view.matches()[1])
        assert any("yellow" in str(span.style) for span in current.spans)
        assert not any("yellow" in str(span.style) for span in other.spans)


async def test_a_linux_console_gets_ascii_state_icons(tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("TERM", "linux")
    async with shown(tmp_path, launch_file(tmp_path, QUIET)) as (app, _pilot, _port):
        label = row(app, "quiet-1")
        assert label.startswith("* ") and "●" not in label


async def test_focus_shows_in_reverse_video_and_one_new_line_is_singular(
        tmp_path: Path) -> None:
    async with shown(tmp_path, launch_file(tmp_path, COUNTER)) as (app, pilot, port):
        tree = app.query_one(LaunchTree)
        await pilot.pause()
        # the focused tree's cursor row is drawn in reverse video: visible with 8 colours
        assert any(seg.style is not None and seg.style.reverse
                   for seg in tree.render_line(0)._segments)
        await pilot.press("down", "down")
        port.tell(counted(0, 31))
        await until(pilot, lambda: last_number(app) >= 30, "line 30 at the bottom")
        view = line_view(app)
        view.focus()
        await pilot.press("up")  # one line up: the newest is just below the pane
        assert not view.following
        assert "1 new line (G: follow)" in pane_status(app)
        port.tell(counted(31, 32))  # one more arrives below
        await until(pilot, lambda: "2 new lines (G: follow)" in pane_status(app), "2 said")
