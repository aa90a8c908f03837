"""What a second hour of demanding use found in the TUI, where it takes a real terminal or
real processes: a line typed with `i` into a stopped node quits nothing; an operator's
restart backs off from the file's delay again; a progress line rewritten with `\\r` shows
as it stands.

The App's own side (keys dropped while another client types, a respawn's countdown and a
root restart's question, a service typed before the list came, the quit question at 40x10)
is tested over an in-memory session in tests/unit/test_app_later_hours.py."""

from __future__ import annotations

import asyncio
import os
import time

import pytest

from tuilaunch.tui.app import make_app
from tuilaunch.tui.key_order import BURST_GAP

from .session_steps import start_here, stop_here
from .test_interact import PROGRAMS
from .test_interact_tui import pane, select
from .test_sessions import detached_with, runtime, status, tl  # noqa: F401  (runtime: a fixture)
from .test_tui import until
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
        # the next burst, typed once the question shows: a person's pause, as a key within
        # key_order.BURST_GAP of the dropped burst would be dropped with it
        time.sleep(3 * BURST_GAP)
        os.write(master, b"yes\r")
        screen += read_until(master, b"got: es")
        assert b"still run" not in screen  # no quit question
        os.write(master, b"\x1d")  # ctrl+]: the keys back
        read_until(master, b"Type")  # the footer offers tuilaunch's keys again
        os.write(master, b"q")  # the quit question counts what still runs: both
        read_until(master, b"2 processes still run")
    finally:
        stop_pty(proc, master)


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
    name = start_here(path)
    try:
        logs = eventually(lambda: tl("logs", name, "flaky-1").stdout,
                          lambda text: "try 4 in" in text)
        assert "try 4 in 2.4 s" in logs, logs  # 0.3, 0.6, 1.2, 2.4: backing off
        assert logs.count("try 1 in 0.3 s") == 1, logs
        tl("restart", name, "flaky-1")
        # the count starts again: try 1 once more (a loaded machine may let the backing off
        # go on to try 5 before the restart comes: the next try 1 is the restart's)
        logs = eventually(lambda: tl("logs", name, "flaky-1").stdout,
                          lambda text: text.count("try 1 in 0.3 s") == 2)
        assert logs.count("try 1 in 0.3 s") == 2, logs
    finally:
        stop_here(name)


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
    stop_here(name)
    log = next(log_dir.glob("fetch-1*.log")).read_bytes()
    # the log keeps the last state of the line (written when its process ended), never
    # 64 KB pieces of its past states
    assert log.count(b"downloading") <= 1, log[:300]
    assert all(len(line) < 4000 for line in log.split(b"\n"))


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


