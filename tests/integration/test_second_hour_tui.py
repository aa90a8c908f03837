"""What a second hour of demanding use found in the TUI: a key typed for a node never
becomes one of tuilaunch's commands when `i` cannot type; a stop or restart of many asks
first; a respawn's wait counts down; a progress line rewritten with `\\r` shows as it
stands."""

from __future__ import annotations

import asyncio
import os
import time

import pytest
from textual.widgets import Input

from tuilaunch.client.link import open_link
from tuilaunch.engine.run.vocabulary.requests import TakeKeys
from tuilaunch.tui.app import make_app
from tuilaunch.tui.screens.dialogs import ConfirmScreen
from tuilaunch.tui.screens.services_panel import ServicesPanel

from .test_interact import LAUNCH, PROGRAMS, process
from .test_interact_tui import pane, select
from .test_sessions import detached_with, runtime, status, tl  # noqa: F401  (runtime: a fixture)
from .test_tui import launched, states, tui, until
from .test_tui_keys import burst
from .test_tui_long_sessions import read_until, start_on_pty, stop_pty

pytestmark = pytest.mark.usefixtures("runtime")  # a private session folder per test


TYPED_TWO = f"""
import sys
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='lines', output='screen', emulate_tty=True,
                       cmd=[sys.executable, {str(PROGRAMS)!r} + '/line_reader.py']),
        ExecuteProcess(name='quiet', cmd=['sleep', '600']),
    ])
"""


def test_a_line_typed_with_i_into_a_stopped_node_quits_nothing(write, tmp_path):
    """On a real terminal, as ssh delivers a typed line: `iquit yes` Enter on a node with a
    terminal that was stopped. Before, `q` asked to quit and `y` answered: the whole launch
    stopped. Now `i` asks whether to start the node and the rest of the burst goes nowhere
    (its `y` does not answer); a `y` typed once the question shows starts it, and what
    follows it is the node's."""
    proc, master = start_on_pty(tmp_path, str(write(TYPED_TWO)))
    try:
        read_until(master, b"2 running")
        os.write(master, b"\x1b[B\x1b[B")  # down to lines-1 (root, all nodes, lines)
        read_until(master, b"lines-1  ")
        os.write(master, b"s")
        read_until(master, b"process stopped [pid")
        os.write(master, b"iquit yes\r")
        screen = read_until(master, b"is not running (exited)")  # what `i` asked
        time.sleep(1.0)  # the next burst: typed once the question shows
        os.write(master, b"yes\r")
        screen += read_until(master, b"got: es")
        assert b"still run" not in screen  # no quit question
        os.write(master, b"\x1d")  # ctrl+]: the keys back
        read_until(master, b"Type")  # the footer offers tuilaunch's keys again
        os.write(master, b"q")  # the quit question counts what still runs: both
        read_until(master, b"2 processes still run")
    finally:
        stop_pty(proc, master)


def test_keys_typed_with_i_are_dropped_while_another_client_types(write):
    """Another client has the node's keyboard: `i` is refused, and the keys typed with it
    (`abc`: a is all nodes' output, c the command line) go nowhere, with one line."""
    path = str(write(LAUNCH))
    name, log_dir = detached_with(path, "lines-1")
    other = open_link(name)
    try:
        other.request(TakeKeys(process="lines-1", on=True))

        async def scenario() -> None:
            app = make_app(path, {}, log_dir, session_name=name)
            async with app.run_test(size=(120, 32)) as pilot:
                await until(pilot, lambda: "ready" in pane(app, "lines-1"))
                await select(pilot, app, "lines-1")
                await pilot.pause()
                shown = app.output_panel.view
                burst(app, "i", *"abc", "s")
                await until(pilot, lambda: any(
                    "were not sent" in str(n.message) for n in app._notifications))
                # the whole burst read and dropped
                await until(pilot, lambda: time.monotonic() >= app.dropping_until)
                assert app.keyboard.typing_to is None
                assert app.output_panel.view == shown  # `a` did not switch to all output
                assert not app.screen_stack[1:]  # `c` opened no command dialog
                assert app.supervisor is not None
                assert app.supervisor.states["lines-1"] == "running"  # `s` stopped nothing
                await pilot.press("d")

        asyncio.run(scenario())
        assert process(name, "lines-1")["state"] == "running"
    finally:
        other.close()
        tl("stop", name)


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


def test_a_respawn_wait_counts_down_and_r_on_the_root_asks(write):
    path = str(write(RESPAWNING))
    name, log_dir = detached_with(path, "quiet-2")

    async def scenario() -> None:
        app = make_app(path, {}, log_dir, session_name=name)
        async with app.run_test(size=(120, 32)) as pilot:
            tree = app.launch_tree
            await until(pilot, lambda: tree.states.get("flaky-1") == "respawning")
            await until(pilot, lambda: tree.details.get("flaky-1", "").startswith("(try "))
            first = tree.details["flaky-1"]
            # the row counts down: a later second shows fewer seconds left
            await until(pilot, lambda: tree.states.get("flaky-1") == "respawning"
                        and tree.details["flaky-1"] != first
                        and tree.details["flaky-1"].startswith("(try "))
            # r on the root asks, as s does; n restarts nothing
            quiet = status(name)
            before = {p["id"]: p["pid"] for p in quiet["processes"] if p["id"] != "flaky-1"}
            tree.focus()
            await pilot.press("home")
            await pilot.press("r")
            await until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
            assert "Restart all 3 processes" in app.screen.question
            await pilot.press("n")
            await until(pilot, lambda: not isinstance(app.screen, ConfirmScreen))
            after = {p["id"]: p["pid"] for p in status(name)["processes"]
                     if p["id"] != "flaky-1"}
            assert after == before
            await pilot.press("d")

    asyncio.run(scenario())
    tl("stop", name)


def eventually(read, test, limit: float = 60.0):
    """Reads until `test` holds of what was read (a deadline, not a sleep)."""
    deadline = time.monotonic() + limit
    while True:
        value = read()
        if test(value) or time.monotonic() > deadline:
            return value
        time.sleep(0.1)


def test_an_operators_restart_backs_off_from_the_files_delay_again(write):
    """After quick crashes in a row the wait doubles; a restart by the operator starts the
    count again: the next wait is the file's respawn_delay, try 1."""
    path = str(write(RESPAWNING.replace("respawn_delay=4.0", "respawn_delay=0.3")))
    name = tl(path, "--detach").stdout.strip()
    try:
        logs = eventually(lambda: tl("logs", name, "flaky-1").stdout,
                          lambda text: "try 4 in" in text)
        assert "try 4 in 2.4 s" in logs, logs  # 0.3, 0.6, 1.2, 2.4: backing off
        tl("restart", name, "flaky-1")
        since = eventually(
            lambda: tl("logs", name, "flaky-1").stdout.rsplit("try 4 in", 1)[-1],
            lambda text: "respawning" in text)
        assert "try 1 in 0.3 s" in since, since
    finally:
        tl("stop", name)


PROGRESS = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
import sys
CODE = '''
import sys, time
for i in range(0, 101):
    sys.stdout.write("\\\\rdownloading %3d%% " % i + "x" * 2000)
    sys.stdout.flush()
    time.sleep(0.02)
    if i == 60:
        open(sys.argv[1], "w").close()
        time.sleep(600)
'''
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='fetch', cmd=[sys.executable, '-c', CODE, MARK],
                       output='screen'),
    ])
"""


def test_a_progress_line_shows_as_it_stands_while_it_is_rewritten(write, tmp_path):
    """A download rewriting its line with \\r and no newline: the pane shows the line's
    current state while it goes on (before: nothing for seconds, then 64 KB pieces cut
    mid-word)."""
    mark = tmp_path / "at60"
    path = str(write(PROGRESS.replace("MARK", repr(str(mark)))))
    name, log_dir = detached_with(path, "fetch-1")

    async def scenario() -> None:
        app = make_app(path, {}, log_dir, session_name=name)
        async with app.run_test(size=(120, 32)) as pilot:
            await select(pilot, app, "fetch-1")
            await until(pilot, lambda: mark.exists(), limit=60)
            await until(pilot, lambda: any("downloading  60%" in line.text
                                           for line in app.store.partials.values()))
            # no piece of the rewritten line became a line of its own
            assert "downloading" not in pane(app, "fetch-1")
            # tab into the pane: its status line says it has the keys
            status_line = app.query_one("#output-status")
            assert not str(status_line.render()).startswith("▶")
            app.output_panel.query_one("LineView").focus()
            await until(pilot, lambda: str(status_line.render()).startswith("▶ fetch-1"))
            await pilot.press("d")

    asyncio.run(scenario())
    tl("stop", name)
    log = next(log_dir.glob("fetch-1*.log")).read_bytes()
    # the log keeps the last state of the line (written when its process ended), never
    # 64 KB pieces of its past states
    assert log.count(b"downloading") <= 1, log[:300]
    assert all(len(line) < 4000 for line in log.split(b"\n"))


async def test_a_service_typed_with_the_tab_key_before_the_list_came_is_picked(tmp_path):
    """`3/ena` Enter in one read, the first time the tab opens: the Enter waits for the
    list (discovery takes a moment) and picks the first match, rather than being lost."""
    async with tui(tmp_path, "robot:=tui6", "listener:=false") as (app, pilot):
        await until(pilot, lambda: states(app).get("service_server-4") == "running")
        burst(app, "3", "slash", *"tui6/enable", "enter")
        await until(pilot, lambda: app.query_one(ServicesPanel))  # made as the tab shows
        panel = app.query_one(ServicesPanel)
        await until(pilot, lambda: panel.selected is not None, limit=60)
        assert panel.selected == ("/tui6/enable", "std_srvs/srv/SetBool")
        # the form is mounted after the pick: its field has the focus once it is there
        await until(pilot, lambda: isinstance(app.focused, Input)
                    and app.focused.id == "field-data")


def test_f_shows_a_programs_own_colours_and_not_a_loggers_level_colour():
    from tuilaunch.tui.output_store import parse
    from tuilaunch.tui.screens.line_view import display_text

    mixed = parse("p", "ok \x1b[31mFAIL\x1b[0m done", "stdout", 0.0).line
    shown = display_text(mixed, False, False, raw=True)
    assert shown.plain == "ok FAIL done"
    assert [(span.start, span.end) for span in shown.spans] == [(3, 7)]  # FAIL in red
    compact = display_text(mixed, False, False, raw=False)
    assert not compact.spans  # the compact form: colours by level only
    # a ROS logger's line in its level's one colour keeps no second copy
    logged = parse("p", "\x1b[32m[INFO] [1.5] [talker]: hi\x1b[0m", "stdout", 0.0).line
    assert logged.colored is None and logged.message == "hi"


async def test_the_quit_dialog_fits_a_40_by_10_terminal(write, tmp_path):
    async with launched(str(write(TYPED_TWO)), {}, tmp_path, (40, 10)) as (app, pilot):
        await until(pilot, lambda: app.supervisor is not None
                    and app.supervisor.states.get("quiet-2") == "running")
        await pilot.press("q")
        await until(pilot, lambda: type(app.screen).__name__ == "QuitScreen")
        await pilot.pause()
        for button in ("#stop", "#keep"):
            region = app.screen.query_one(button).region
            assert region.right <= 40 and region.bottom <= 10, (button, region)
        await pilot.press("y")
        await until(pilot, lambda: not app.supervisor.pids, limit=60)
