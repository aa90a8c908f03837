"""The TUI over long sessions and slow links, where it takes real processes: floods keep the
panes moving, the terminal gets only what changed, keys written to a real terminal in one
write keep their order, a relaunch's exit and a group's restart as the session runs them,
the Params tab over a node's own parameters, a stubborn process killed at once.

The App's own side of these (a scrollback, repaints, keys in one read, refused values,
80x24, process events in the panes, follow, the tab keys) is tested over an in-memory
session in tests/unit/test_app_long_sessions.py."""

from __future__ import annotations

import os
import pty
import select
import subprocess
import sys
import time
from collections.abc import AsyncIterator, Iterator
from contextlib import asynccontextmanager, contextmanager
from pathlib import Path

import pytest
from textual.pilot import Pilot
from textual.widgets import DataTable

from tuilaunch.tui.app import TuiLaunchApp, make_app
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.dialogs import ConfirmScreen
from tuilaunch.tui.screens.fields import Field
from tuilaunch.tui.screens.output_panel import OutputPanel
from tuilaunch.tui.screens.params_panel import ParamsPanel
from tuilaunch.tui.screens.tree_panel import LaunchTree

from ..conftest import session_folders
from .proc_tree import end, servers_of
from .session_steps import start_here, stop_here
from .test_sessions import status, wait_state
from .test_tui import BRINGUP, launched, pids, row_text, states, tab_panel, until

COUNTER = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    code = ('import sys, time\\n'
            'for i in range({count}):\\n'
            '    print(f"[INFO] [{{time.time():.3f}}] [counter]: line {{i}}", flush=True)\\n'
            '    time.sleep({pause})\\n'
            'time.sleep(600)\\n')
    return LaunchDescription([ExecuteProcess(name=f'counter{{k}}', cmd=[{python!r}, '-c', code])
                              for k in range({copies})])
"""


def counter_file(write, count: int, pause: float, copies: int = 1) -> Path:
    return write(COUNTER.format(count=count, pause=pause, copies=copies,
                                python=sys.executable), "counter.py")


def panel_of(app: TuiLaunchApp) -> OutputPanel:
    return app.query_one(OutputPanel)


def last_number(app: TuiLaunchApp) -> int:
    """The line number on the pane's bottom row, as a user reads it."""
    rows = [r for r in panel_of(app).line_view.visible_text() if "line " in r]
    return int(rows[-1].rsplit("line ", 1)[1]) if rows else -1


# --- 1. the pane never freezes ---------------------------------------------------------


async def test_four_flooders_keep_the_all_nodes_pane_moving(write, tmp_path):
    # a flood that outlasts the test however fast the machine is (stopped at its end)
    path = counter_file(write, 10**8, 0, copies=4)
    async with launched(str(path), {}, tmp_path, (80, 24), scrollback=200) as (app, pilot):
        assert panel_of(app).view.process is None
        await until(pilot, lambda: last_number(app) > 0)
        samples = [tuple(panel_of(app).line_view.visible_text())]
        for _ in range(4):
            # the pane repaints about once a second; a busy machine may take longer, so
            # each look waits for the next repaint rather than for a fixed time
            await until(pilot, lambda: tuple(panel_of(app).line_view.visible_text())
                        != samples[-1])
            samples.append(tuple(panel_of(app).line_view.visible_text()))
        assert len(set(samples)) == 5  # every look shows new lines


# --- 2. quiet on the wire ----------------------------------------------------------------


QUIET = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='quiet', cmd=['sleep', '600'])])
"""


LOG_DIRS: dict[int, Path] = {}
"""Each TUI started on a pty, by pid: the folder its launch logs into (ROS_LOG_DIR)."""


def start_on_pty(tmp_path: Path, *argv: str, size: tuple[int, int] = (80, 24)) \
        -> tuple[subprocess.Popen[bytes], int]:
    import fcntl
    import struct
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", size[1], size[0], 0, 0))
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path), "TERM": "xterm-256color"}
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", *argv], stdin=slave,
                            stdout=slave, stderr=slave, env=env, start_new_session=True)
    os.close(slave)
    LOG_DIRS[proc.pid] = tmp_path
    return proc, master


def read_for(master: int, seconds: float) -> bytes:
    out = b""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if select.select([master], [], [], 0.05)[0]:
            try:
                out += os.read(master, 65536)
            except OSError:
                break
    return out


def read_until(master: int, marker: bytes, limit: float = 60) -> bytes:
    out = b""
    end = time.monotonic() + limit
    while marker not in out:
        assert time.monotonic() < end, f"{marker!r} never shown; the TUI wrote: {out[-3000:]!r}"
        if select.select([master], [], [], 0.1)[0]:
            try:
                out += os.read(master, 65536)
            except OSError:  # the terminal's far side closed: the TUI ended
                raise AssertionError(f"the TUI ended before {marker!r}; it wrote: "
                                     f"{out[-3000:]!r}") from None
    return out


def stop_pty(proc: subprocess.Popen[bytes], master: int) -> None:
    proc.terminate()
    read_for(master, 0.5)
    try:
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, 9)
            proc.wait()
        os.close(master)
        # a TUI killed before it stopped its launch leaves the server (a session of its own)
        log_dir = LOG_DIRS.pop(proc.pid, None)
        if log_dir is not None:
            end(servers_of(log_dir))


def test_an_unchanging_screen_sends_almost_nothing_to_the_terminal(write, tmp_path):
    """Nothing changes on screen: no repaints of identical content (was 53 KB/s)."""
    proc, master = start_on_pty(tmp_path, str(write(QUIET)))
    try:
        read_until(master, b"1 running")
        read_for(master, 1.5)  # the first screen settles
        quiet = read_for(master, 4.0)
        assert len(quiet) < 4 * 300, f"{len(quiet)} bytes in 4 s with nothing changing"
    finally:
        stop_pty(proc, master)


# --- 3. keys that arrive together --------------------------------------------------------


def test_keys_written_to_a_real_terminal_in_one_write_keep_their_order(write, tmp_path):
    """The same over a real pseudo-terminal: the preview names the value typed last."""
    path = write("""
        from simple_launch import SimpleLauncher
        def generate_launch_description():
            sl = SimpleLauncher()
            sl.declare_arg('count', 7, description='how many')
            sl.node('tuilaunch_demos', 'talker', parameters={'count': sl.arg('count')})
            return sl.launch_description()
        """)
    proc, master = start_on_pty(tmp_path, str(path))
    try:
        read_until(master, b"1 running")
        os.write(master, b"2")
        read_until(master, b"how many")
        # into the field (one tab past Apply and Defaults), erase it, type 42, erase one,
        # type 3
        os.write(master, b"\t" + b"\x15" + b"42" + b"\x7f" + b"3")
        screen = read_until(master, b"F5 applies")
        assert b"count:=" not in screen
        os.write(master, b"\x1b[15~")  # F5
        read_until(master, b"count:=43")
    finally:
        stop_pty(proc, master)


# --- 4. values the plan cannot use -------------------------------------------------------


async def test_a_node_that_exits_1_after_a_relaunch_shows_failed_with_its_code(write, tmp_path):
    path = write("""
        from launch import LaunchDescription
        from launch.actions import DeclareLaunchArgument, ExecuteProcess
        from launch.substitutions import LaunchConfiguration
        def generate_launch_description():
            return LaunchDescription([
                DeclareLaunchArgument('code', default_value='0'),
                ExecuteProcess(name='job', cmd=['sh', '-c', 'sleep 0.3; exit $0',
                                                LaunchConfiguration('code')])])
        """)
    async with launched(str(path), {}, tmp_path, (80, 24)) as (app, pilot):
        await until(pilot, lambda: "exited" in row_text(app, "job-1"))
        await pilot.press("2")
        app.query_one("#arg-code", Field).value = "1"
        await pilot.pause()
        await pilot.press("f5")
        await until(pilot, lambda: "failed" in row_text(app, "job-1"))
        assert "exit code 1" in row_text(app, "job-1")
        assert "1 failed" in str(app.query_one("#status").render())


# --- 9. group restart re-runs its actions; 10. the Params tab -----------------------------

BRINGUP_ARGUMENTS = {"robot": "tuig", "services": "false", "listener": "false",
                     "mode": "dock"}


@pytest.fixture(scope="module")
def bringup(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path]]:
    """One session of examples/bringup.py (BRINGUP_ARGUMENTS) for the tests that attach a
    TUI to it to look at one thing: its name and its log folder. A test may restart its
    nodes (their pids change), nothing else of it; it is stopped at the end of the module."""
    root = tmp_path_factory.mktemp("bringup")
    with session_folders(root / "log"):
        name = start_here(BRINGUP, *(f"{k}:={v}" for k, v in BRINGUP_ARGUMENTS.items()))
        try:
            wait_state(name, "configurable-3", "running")
            yield name, Path(status(name)["log_dir"])
        finally:
            stop_here(name, gone_ok=True)
            end(servers_of(root / "log"))


@asynccontextmanager
async def attached_to(bringup: tuple[str, Path]) -> AsyncIterator[tuple[TuiLaunchApp, Pilot]]:
    """A TUI attached to the module's session, as `tuilaunch attach` opens it; it detaches
    at the end (the session runs on)."""
    name, log_dir = bringup
    app = make_app(BRINGUP, BRINGUP_ARGUMENTS, log_dir, session_name=name)
    async with app.run_test(size=(100, 32)) as pilot:
        yield app, pilot
        await pilot.press("d")


async def test_restarting_a_group_reruns_its_set_parameters(bringup):
    async with attached_to(bringup) as (app, pilot):
        await until(pilot, lambda: states(app).get("set_parameters-1") == "done")
        log = View("configurable-3")
        await until(pilot, lambda: any("mode set to 'dock'" in line
                                       for line in app.store.text(log)))
        tree = app.query_one(LaunchTree)
        group = tree.rows["configurable-3"].parent
        assert group is not None
        tree.move_cursor(group)
        await pilot.pause()
        first = pids(app)["configurable-3"]
        await pilot.press("r")
        await until(pilot, lambda: pids(app).get("configurable-3") not in (None, first))
        # after its new start line, the node reports the launch file's value again
        await until(pilot, lambda: any("mode set to 'dock'" in line for line in
                                       app.store.text(log)[_last_start(app.store.text(log)):]),
                    limit=60)


def _last_start(lines: list[str]) -> int:
    return max(i for i, line in enumerate(lines) if "process started" in line)


async def test_params_launch_column_matches_a_node_by_the_name_it_reports(bringup):
    async with attached_to(bringup) as (app, pilot):
        # configurable has no name in the launch file (plan full_name is None)
        assert app.session.plan.process("configurable-3").full_name is None
        await until(pilot, lambda: states(app).get("set_parameters-1") == "done")
        panel = await tab_panel(pilot, app, "4", ParamsPanel)
        await until(pilot, lambda: "/tuig/control/configurable" in panel.nodes,
                    every=panel.refresh_listing)
        panel.load_node("/tuig/control/configurable")
        table = app.query_one("#prm-table", DataTable)
        await until(pilot, lambda: "mode" in panel.params and table.row_count > 0)
        assert table.get_cell("mode", "launch") == "idle"  # the node's own parameters
        # after a set, typing replaces the value instead of appending to it
        table.move_cursor(row=list(panel.params).index("mode"))
        await pilot.pause()
        edit = app.query_one("#prm-edit", Field)
        edit.value = "dock"
        edit.focus()
        await pilot.press("enter")
        await until(pilot, lambda: "now reports dock" in str(
            app.query_one("#prm-result").render()))
        await pilot.press(*"idle")
        assert edit.value == "idle"


# --- 11. flood notices are counted, not lines --------------------------------------------------


async def test_lines_not_drawn_are_counted_in_the_status_not_written_as_warnings(write,
                                                                               tmp_path):
    path = counter_file(write, 20000, 0)

    def tiny_budget(app: TuiLaunchApp) -> None:
        app.buffer.max_lines = 50  # a tiny per-tick budget, so the flood overflows it

    async with launched(str(path), {}, tmp_path, (80, 24), prepare=tiny_budget) as (app, pilot):
        await until(pilot, lambda: app.store.dropped.total > 0)
        await until(pilot, lambda: "not drawn (in log)"
                    in str(app.query_one("#output-status").render()))
        assert not any("not shown" in line.text or line.level >= 2
                       for line in app.store.lines(View()))
    # the log file has every line the process printed
    log = next((tmp_path / "log").glob("counter0-1.log")).read_text()
    assert "line 0\n" in log


# --- 12. smaller things -----------------------------------------------------------------------


async def test_a_second_q_while_a_stubborn_process_stops_offers_to_kill_it(write, tmp_path):
    path = write("""
        from launch import LaunchDescription
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            return LaunchDescription([ExecuteProcess(name='stubborn', cmd=[
                'sh', '-c', 'trap "" INT TERM; echo holding out; sleep 600'])])
        """)
    async with launched(str(path), {"sigterm_timeout": "30", "sigkill_timeout": "30"}, tmp_path,
                        (80, 24)) as (app, pilot):
        await until(pilot, lambda: any("holding out" in line
                                       for line in app.store.text(View("stubborn-1"))))
        await pilot.press("q", "y")
        await until(pilot, lambda: "SIGINT sent" in str(app.query_one("#status").render()))
        await pilot.press("q")
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("y")
        # well before the 30 s SIGTERM/SIGKILL timeouts: the kill was immediate
        await until(pilot, lambda: not pids(app), limit=25)


ONE_ARGUMENT = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
def generate_launch_description():
    return LaunchDescription([DeclareLaunchArgument('label', default_value='x'),
                              ExecuteProcess(name='quiet', cmd=['sleep', '600'])])
"""


@contextmanager
def arguments_tab_on_a_pty(write, tmp_path) -> Iterator[int]:
    """A launch of one argument run on a real pty, its Arguments tab (2) shown: the pty's
    master end; the launch is stopped afterwards."""
    proc, master = start_on_pty(tmp_path, str(write(ONE_ARGUMENT)))
    try:
        read_until(master, b"1 running")
        os.write(master, b"2")
        read_until(master, b"Apply (F5)")
        yield master
    finally:
        stop_pty(proc, master)


def test_escape_and_a_digit_in_one_write_leave_the_field_and_switch_tabs(write, tmp_path):
    """Over a real terminal ESC+3 in one read is parsed as one key: still leave, then 3."""
    with arguments_tab_on_a_pty(write, tmp_path) as master:
        os.write(master, b"\x1b3")
        screen = read_until(master, b"services")
        assert "£".encode() not in screen


def test_escape_and_a_letter_in_one_write_leave_the_field_then_act(write, tmp_path):
    """ESC+/ in one read (escape then `/` typed fast over ssh) is parsed as alt+/: it leaves
    the field, then `/` opens the search, instead of typing `/` into the field."""
    with arguments_tab_on_a_pty(write, tmp_path) as master:
        os.write(master, b"\t")  # into the label field (one tab past Apply, Defaults)
        os.write(master, b"y\x1bq")  # type y, then escape and q together: leave, then quit
        screen = read_until(master, b"and quit?")
        assert b"yq" not in screen  # the q was not typed into the field
