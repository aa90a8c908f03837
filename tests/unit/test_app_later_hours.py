"""What the second and third hours of demanding use found in the TUI, its own side over an
in-memory session (moved from tests/integration/test_second_hour_tui.py and
test_third_hour_tui.py, which keep what a real terminal, a session's refusal or a real
process shows): a key typed for a node never becomes one of tuilaunch's commands when `i`
cannot type; a stop, restart or quit of many asks first and opens on its safe answer; a
respawn's wait counts down; a read-only view offers no key it refuses; a service typed with
the tab key waits for the list; the quit question fits 40x10."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from textual import events
from textual.widgets import Input

from tests.unit.pilot_sessions import (
    burst,
    burst_dropped,
    dialogs,
    keys_handled,
    launch_file,
    shown,
    toasts,
)
from tests.unit.test_app_pilot import footer, select, until
from tuilaunch.engine.run.events import ExitCause, ProcessExited, Respawning, Typing
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.key_order import BURST_GAP
from tuilaunch.tui.nodes import respawn_countdown
from tuilaunch.tui.screens.dialogs import ConfirmScreen
from tuilaunch.tui.screens.services_panel import ServicesPanel

COMMANDS = {"stop", "restart", "start", "shutdown", "typing", "input"}
"""What a key typed for a node must never ask of the session when `i` cannot type."""

TYPED_TWO = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='lines', output='screen', emulate_tty=True, cmd=['line_reader']),
        ExecuteProcess(name='quiet', cmd=['sleep', '600']),
    ])
"""


# --- the second hour ------------------------------------------------------------------------


async def test_keys_typed_with_i_are_dropped_while_another_client_types(tmp_path: Path) -> None:
    """Another client has the node's keyboard: `i` is refused, and the keys typed with it
    (`abc`: a is all nodes' output, c the command line) go nowhere, with one line."""
    def refuse(**_: object) -> None:
        raise SessionError("session two: another client (client 2) is typing into lines-1; "
                           "one client types at a time")

    async with shown(tmp_path, launch_file(tmp_path, TYPED_TWO), name="two") \
            as (app, pilot, port):
        port.answers["status"] = lambda **_: {"processes": [
            {"id": "lines-1", "state": "running", "terminal": True}]}
        port.answers["typing"] = refuse
        port.tell(Typing("lines-1", data={"client": 2}))
        select(app, "lines-1")
        await until(pilot, lambda: app.output_panel.view.process == "lines-1", "its pane")
        view = app.output_panel.view
        burst(app, "i", *"abc", "s")
        await until(pilot, lambda: any("were not sent" in t for t in toasts(app)), "said")
        await burst_dropped(pilot, app)  # the whole burst read and dropped
        assert app.keyboard.typing_to is None
        assert app.output_panel.view == view  # `a` did not switch to all output
        assert dialogs(app) == []  # `c` opened no command dialog
        assert "stop" not in port.ops()  # `s` stopped nothing


RESPAWNING = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='flaky', cmd=['sh', '-c', 'echo up; exit 3'], respawn=True,
                       respawn_delay=4.0, output='screen'),
        ExecuteProcess(name='quiet', cmd=['sleep', '600']),
        ExecuteProcess(name='quiet2', cmd=['sleep', '600']),
    ])
"""


async def test_a_respawn_wait_counts_down_and_r_on_the_root_asks(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    now = [1000.0]  # the wait is counted on a clock the test moves (as test_app_tree's)
    monkeypatch.setattr(respawn_countdown, "monotonic", lambda: now[0])
    async with shown(tmp_path, launch_file(tmp_path, RESPAWNING)) as (app, pilot, port):
        tree = app.launch_tree
        port.tell(ProcessExited("flaky-1", pid=1000, code=3, reason="exit code 3",
                                cause=ExitCause.CRASHED),
                  Respawning("flaky-1", reason="respawn in 4 s", data={"try": 1, "delay": 4.0}))
        await until(pilot, lambda: tree.details.get("flaky-1", "").startswith("(try "),
                    "the wait on its row")
        first = tree.details["flaky-1"]
        now[0] += 1.0
        # the row counts down: a later second shows fewer seconds left
        await until(pilot, lambda: tree.details["flaky-1"] != first
                    and tree.details["flaky-1"].startswith("(try "), "counted down")
        # r on the root asks, as s does; n restarts nothing
        tree.focus()
        await pilot.press("home")
        await pilot.press("r")
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "the question")
        assert "Restart all 3 processes" in app.screen.question
        await pilot.press("n")
        await until(pilot, lambda: not isinstance(app.screen, ConfirmScreen), "answered")
        await keys_handled(pilot, app)
        assert "restart" not in port.ops()


async def test_a_service_typed_with_the_tab_key_before_the_list_came_is_picked(
        tmp_path: Path) -> None:
    """`3/ena` Enter in one read, the first time the tab opens: the Enter waits for the
    list (discovery takes a moment) and picks the first match, rather than being lost."""
    async with shown(tmp_path, arguments={"robot": "tui6", "listener": "false"}) \
            as (app, pilot, port):
        discovered: list[tuple[str, list[str]]] = []
        port.answers["services"] = lambda **_: {"services": discovered}
        port.answers["service_fields"] = lambda **_: {"fields": [
            {"name": "data", "type": "boolean", "default": False, "is_sequence": False}]}
        burst(app, "3", "slash", *"tui6/enable", "enter")
        await until(pilot, lambda: app.query(ServicesPanel)
                    and app.query_one(ServicesPanel)._submit_waits, "the Enter waiting")
        panel = app.query_one(ServicesPanel)
        assert panel.selected is None
        discovered.append(("/tui6/enable", ["std_srvs/srv/SetBool"]))  # discovered now
        await until(pilot, lambda: panel.selected is not None, "a service picked")
        assert panel.selected == ("/tui6/enable", "std_srvs/srv/SetBool")
        # the form is mounted after the pick: its field has the focus once it is there
        await until(pilot, lambda: isinstance(app.focused, Input)
                    and app.focused.id == "field-data", "its field focused")


async def test_the_quit_dialog_fits_a_40_by_10_terminal(tmp_path: Path) -> None:
    async with shown(tmp_path, launch_file(tmp_path, TYPED_TWO), size=(40, 10)) \
            as (app, pilot, port):
        await pilot.press("q")
        await until(pilot, lambda: dialogs(app) == ["QuitScreen"], "the question")
        await pilot.pause()
        for button in ("#stop", "#keep"):
            region = app.screen.query_one(button).region
            assert region.right <= 40 and region.bottom <= 10, (button, region)
        await pilot.press("y")
        await until(pilot, lambda: "shutdown" in port.ops(), "the launch stopped")


# --- the third hour ------------------------------------------------------------------------

THREE = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, GroupAction
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('listener', default_value='true'),
        GroupAction([
            ExecuteProcess(name='talker', cmd=['sleep', '600']),
            GroupAction([ExecuteProcess(name='listener', cmd=['sleep', '600'])],
                        condition=IfCondition(LaunchConfiguration('listener'))),
            ExecuteProcess(name='piped', cmd=['sleep', '600']),
        ]),
    ])
"""


async def on_row(pilot, app: TuiLaunchApp, line: int) -> None:  # type: ignore[no-untyped-def]
    """The tree's cursor `line` rows below the root (all nodes 1, the group 2, talker-1 3,
    the condition 4, listener-2 5, piped-3 6), after the burst before it was over (a
    dropped burst goes on until a pause, as a person's next keys come after reading)."""
    await burst_dropped(pilot, app)
    app.launch_tree.focus()
    app.launch_tree.cursor_line = line
    await until(pilot, lambda: app.launch_tree.cursor_line == line, f"row {line}")


def three(tmp_path: Path, **options: object):  # type: ignore[no-untyped-def]
    return shown(tmp_path, launch_file(tmp_path, THREE, "three.launch.py"),
                 {"listener": "false"}, name="three", size=(140, 30), **options)


async def test_keys_typed_with_i_on_a_row_that_is_not_a_node_are_never_commands(
        tmp_path: Path) -> None:
    """`iquit yes` Enter on the root quit the launch; `istop` Enter on a group or on all
    nodes stopped every process (its question opened with Stop focused). Now `i` says at
    once that the row is not a node, and the rest of the burst goes nowhere."""
    async with three(tmp_path) as (app, pilot, port):
        await on_row(pilot, app, 0)  # the root
        burst(app, "i", *"quit yes", "enter")
        await until(pilot, lambda: any("is the launch, not a node" in t for t in toasts(app)),
                    "the root is no node")
        for line, said in ((1, "is every node's output, not a node"),
                           (2, "is a group, not a node"),
                           (4, "is a group, not a node")):  # all nodes, the group, the condition
            await on_row(pilot, app, line)
            before = len(toasts(app))
            burst(app, "i", *"stop", "enter")
            await until(pilot, lambda said=said, before=before: any(
                said in t for t in toasts(app)[before:]), said)
        await burst_dropped(pilot, app)
        await keys_handled(pilot, app)
        assert dialogs(app) == [] and not app.quitting
        assert not COMMANDS & set(port.ops())  # nothing stopped, nothing restarted


async def test_a_burst_is_told_by_when_its_keys_were_read_not_by_when_their_turn_came(
        tmp_path: Path) -> None:
    """A loaded machine delays the keys' turns, not their reading: `istop` read in one
    burst, whose `stop` gets its turn a second after `i` was refused, is still dropped (its
    `s` asked to stop the group when the gap was taken at the turn); a key read after
    a real pause, though its turn comes at once, is a command again."""
    async with three(tmp_path) as (app, pilot, port):
        await on_row(pilot, app, 2)  # a group
        i_read = events.Key("i", "i")
        app.post_message(i_read)
        await until(pilot, lambda: any("is a group, not a node" in t for t in toasts(app)),
                    "i refused")
        await until(pilot, lambda: time.monotonic() > i_read.time + 1, "a second later")
        for key in "stop":  # read with the i, their turn only now
            read = events.Key(key, key)
            read.time = i_read.time + 0.05
            app.post_message(read)
        await keys_handled(pilot, app)
        assert dialogs(app) == [] and not COMMANDS & set(port.ops())
        assert app.tabs.active == "nodes"
        after_pause = events.Key("2", "2")  # read after a pause, its turn with the burst's
        after_pause.time = i_read.time + 0.05 + BURST_GAP + 0.1
        app.post_message(after_pause)
        await until(pilot, lambda: app.tabs.active == "args", "2 shows the Args tab")
        assert not COMMANDS & set(port.ops())


async def test_questions_that_stop_or_quit_open_on_the_safe_answer(tmp_path: Path) -> None:
    """Enter alone answers No: `s` on a group, then Enter, stops nothing; `q`, then Enter,
    keeps the TUI and the launch; `n` in the quit question keeps running (it never
    detaches)."""
    async with three(tmp_path) as (app, pilot, port):
        await on_row(pilot, app, 2)  # the group: a stop of several asks first
        burst(app, "s")
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "the question")
        assert app.screen.question.startswith("Stop all 2 running processes")
        burst(app, "enter")
        await until(pilot, lambda: dialogs(app) == [], "the question answered")
        for answer in ("enter", "n"):
            burst(app, "q")
            await until(pilot, lambda: dialogs(app) == ["QuitScreen"], "the quit question")
            burst(app, answer)
            await until(pilot, lambda: dialogs(app) == [], "the quit question answered")
        await keys_handled(pilot, app)
        assert not app.quitting and not port.detached  # neither quit nor detached
        assert not COMMANDS & set(port.ops())


async def test_a_read_only_view_offers_no_key_it_refuses_and_i_refuses_at_once(
        tmp_path: Path) -> None:
    async with three(tmp_path, read_only=True) as (app, pilot, port):
        await until(pilot, lambda: "Detach" in footer(app), "the tree's keys offered")
        offered = footer(app)
        for refused in ("Stop", "Restart", "Start", "Type", "Debug"):
            assert refused not in offered, offered
        await on_row(pilot, app, 3)  # talker-1
        burst(app, "i", *"quit", "enter")
        await until(pilot, lambda: any("read-only view: typing into a node is refused" in t
                                       for t in toasts(app)), "i refused")
        await on_row(pilot, app, 3)  # a burst of its own
        burst(app, "g")
        await until(pilot, lambda: any("running a node under a tool is refused" in t
                                       for t in toasts(app)), "g refused")
        await burst_dropped(pilot, app)
        await keys_handled(pilot, app)
        assert not app.quitting and not port.detached  # the q of `iquit` did not leave
        assert not COMMANDS & set(port.ops())
