"""The TUI over long sessions and slow links: panes never freeze, the terminal gets only what
changed, typed keys are applied in order, values the plan cannot use are refused, 80x24 stays
readable, process events reach the panes, follow holds, and the keys work from everywhere."""

from __future__ import annotations

import os
import pty
import re
import select
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from textual import events
from textual.widgets import DataTable

from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.dialogs import ConfirmScreen
from tuilaunch.tui.screens.fields import Field
from tuilaunch.tui.screens.output_panel import OutputPanel
from tuilaunch.tui.screens.params_panel import ParamsPanel
from tuilaunch.tui.screens.tree_panel import LaunchTree

from .proc_tree import end, servers_of
from .test_tui import launched, pids, row_text, states, tab_panel, tui, until

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


def burst(app: TuiLaunchApp, *keys: str) -> None:
    """Keys as one read from the terminal delivers them: posted together, nothing run in
    between (Pilot.press waits after each key, which hides ordering faults)."""
    for key in keys:
        char = key if len(key) == 1 else None
        app.post_message(events.Key(key, char))


# --- 1. the pane never freezes ---------------------------------------------------------


async def test_soak_a_small_scrollback_keeps_showing_the_newest_lines(write, tmp_path):
    """scrollback 100 and 1500 lines: the pane must show the newest line all along, not
    stop at the 100th."""
    # 7.5 s of output: the pane repaints about once a second while lines pour in, so even
    # on a loaded machine it is seen to move several times after it is full
    path = counter_file(write, 1500, 0.005)
    async with launched(str(path), {}, tmp_path, (80, 24), scrollback=100) as (app, pilot):
        await pilot.press("down", "down")  # the counter's own pane
        assert panel_of(app).view.process == "counter0-1"
        seen = []
        deadline = time.monotonic() + 60
        while len(app.store.lines(View("counter0-1"))) < 100 or last_number(app) < 1499:
            assert time.monotonic() < deadline, f"pane stuck at {last_number(app)}"
            await pilot.pause(0.2)
            seen.append(last_number(app))
        # it kept moving past the scrollback, and shows the very last line
        assert max(seen) == 1499 and len({n for n in seen if n > 100}) >= 3
        assert len(panel_of(app).line_view.lines) == 100
        assert panel_of(app).line_view.following


async def test_a_search_past_the_scrollback_says_where_the_older_lines_are(write, tmp_path):
    """A search for a line the pane no longer holds does not just say "no line matches":
    it says how many lines the pane keeps and that the log files have them all."""
    path = counter_file(write, 300, 0)
    async with launched(str(path), {}, tmp_path, (80, 24), scrollback=100) as (app, pilot):
        await pilot.press("down", "down")  # the counter's own pane
        await until(pilot, lambda: last_number(app) == 299)
        assert len(panel_of(app).line_view.lines) == 100  # lines 200 to 299
        panel_of(app).set_search("line 3")  # lines 3 and 30-39: only in the log file now
        await pilot.pause()
        said = [n.message for n in app._notifications]
        assert said[-1].startswith("no line matches 'line 3' in the 100 lines this pane "
                                   "keeps; every line is in the log files")


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
        assert time.monotonic() < end, f"{marker!r} never shown"
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


async def test_the_pane_repaints_only_when_its_lines_change(write, tmp_path):
    path = counter_file(write, 3, 0.01)
    async with launched(str(path), {}, tmp_path, (80, 24)) as (app, pilot):
        await until(pilot, lambda: last_number(app) == 2)
        await pilot.pause(1.5)
        view = panel_of(app).line_view
        before = view.repaints
        await pilot.pause(2.0)
        assert view.repaints == before  # nothing new: nothing drawn


# --- 3. keys that arrive together --------------------------------------------------------


async def test_keys_in_one_read_are_applied_in_order_and_f5_applies_what_was_typed(tmp_path):
    async with tui(tmp_path, "robot:=tuik", "services:=false", "listener:=false",
                   size=(80, 24)) as (app, pilot):
        await until(pilot, lambda: states(app).get("talker-1") == "running")
        talker = pids(app)["talker-1"]
        await pilot.press("2")
        field = app.query_one("#arg-rate", Field)
        field.focus()
        await pilot.pause()
        # 26 backspace+letter pairs in one read: every letter replaces the one before
        burst(app, "end", *[k for letter in "abcdefghijklmnopqrstuvwxyz" for k in ("backspace",
                                                                               letter)])
        await until(pilot, lambda: field.value == "2.z")
        # ctrl+u, 3, F5 in one read: the node gets rate 3, not an empty value
        burst(app, "ctrl+u", "3", "f5")
        await until(pilot, lambda: app.session.arguments.get("rate") == "3")
        await until(pilot, lambda: states(app)["talker-1"] == "running"
                    and pids(app).get("talker-1") != talker)
        await until(pilot, lambda: any('"rate": 3' in line for line in
                                       app.store.text(View("talker-1"))))


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
        read_for(master, 0.3)
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


async def test_the_preview_refuses_bad_names_and_f5_applies_nothing(tmp_path):
    async with tui(tmp_path, "robot:=tuin", "services:=false") as (app, pilot):
        await until(pilot, lambda: states(app).get("talker-1") == "running")
        talker = pids(app)["talker-1"]
        await pilot.press("2")
        preview = app.query_one("#args-preview")
        for name, value, why in (("robot", "bad ns!", "namespace '/bad ns!'"),
                                 ("robot", "9lives", "namespace '/9lives'")):
            field = app.query_one(f"#arg-{name}", Field)
            field.value = value
            await pilot.pause()
            assert preview.has_class("error") and why in str(preview.render()), value
            await pilot.press("f5")
            await pilot.pause(0.3)
            assert app.session.arguments == {"robot": "tuin", "services": "false"}
            assert pids(app)["talker-1"] == talker
            field.value = app.session.arguments.get(name, "2.0")
            await pilot.pause()


async def test_an_int_field_warns_of_a_fraction_and_applies_it_as_ros2_launch_would(
        write, tmp_path):
    path = write("""
        from simple_launch import SimpleLauncher
        def generate_launch_description():
            sl = SimpleLauncher()
            sl.declare_arg('copies', 1, description='how many')
            sl.node('tuilaunch_demos', 'talker', name='t')
            return sl.launch_description()
        """)
    async with launched(str(path), {}, tmp_path, (80, 24)) as (app, pilot):
        await pilot.press("2")
        field = app.query_one("#arg-copies", Field)
        field.focus()
        await pilot.press("end", "backspace", *"1.5")
        assert field.value == "1.5"  # not 15: the point is kept
        preview = app.query_one("#args-preview")
        assert "Warning: argument 'copies' = '1.5' is not a whole number like its default 1" \
            in str(preview.render())
        assert not preview.has_class("error")
        await pilot.press("f5")  # launch arguments are strings: ros2 launch takes copies:=1.5
        await until(pilot, lambda: app.session.arguments.get("copies") == "1.5")


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


# --- 5. readable at 80x24 ------------------------------------------------------------------


async def test_at_80x24_the_message_is_on_screen_and_the_split_adapts(tmp_path):
    async with tui(tmp_path, "robot:=tuiw", "services:=false", size=(80, 24)) as (app, pilot):
        tree = app.query_one(LaunchTree)
        assert 22 <= tree.outer_size.width <= 30
        await pilot.press("down", "down", "down")
        assert panel_of(app).view.process == "talker-1"
        await until(pilot, lambda: any(r.startswith('I Publishing: "tuiw says hi')
                                       for r in panel_of(app).line_view.visible_text()))
        width = tree.outer_size.width
        await pilot.press("greater_than_sign")
        await pilot.pause()
        assert tree.outer_size.width == width + 4
        await pilot.press("less_than_sign", "less_than_sign")
        await pilot.pause()
        assert tree.outer_size.width == width - 4
        # timestamps on a toggle, the full line as printed on another
        await pilot.press("T")
        await until(pilot, lambda: re.match(r"\d\d:\d\d:\d\d\.\d{3} I Publishing",
                                            panel_of(app).line_view.visible_text()[-1]))
        await pilot.press("T", "f")
        await until(pilot, lambda: panel_of(app).line_view.visible_text()[-1].startswith(
            "[INFO] ["))


async def test_the_split_is_wider_on_a_wider_terminal(write, tmp_path):
    async with launched(str(write(QUIET)), {}, tmp_path, (120, 40)) as (app, pilot):
        await pilot.pause()
        assert app.query_one(LaunchTree).outer_size.width == 42


async def test_wrap_shows_a_long_line_whole(write, tmp_path):
    path = write("""
        from launch import LaunchDescription
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            return LaunchDescription([ExecuteProcess(name='long', cmd=[
                'sh', '-c', 'echo start-' + 'x' * 150 + '-end; sleep 600'])])
        """)
    async with launched(str(path), {}, tmp_path, (80, 24)) as (app, pilot):
        await pilot.press("down", "down")
        view = panel_of(app).line_view
        await until(pilot, lambda: any("start-" in r for r in view.visible_text()))
        assert not any("-end" in r for r in view.visible_text())
        await pilot.press("z")
        rows = view.visible_text()
        assert any("-end" in r for r in rows) and "wrap" in str(
            app.query_one("#output-status").render())


# --- 6. process events in the panes ---------------------------------------------------------


async def test_a_failed_nodes_pane_says_how_it_died_and_its_reason_is_on_screen(write,
                                                                              tmp_path):
    path = write("""
        from launch import LaunchDescription
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            return LaunchDescription([
                ExecuteProcess(name='crash', cmd=['sh', '-c', 'sleep 0.2; exit 3']),
                ExecuteProcess(name='absent', cmd=['no-such-command-tui']),
                ExecuteProcess(name='fine', cmd=['sleep', '600'])])
        """)
    async with launched(str(path), {}, tmp_path, (80, 24)) as (app, pilot):
        await until(pilot, lambda: "failed" in row_text(app, "crash-1"))
        crash = app.store.text(View("crash-1"))
        assert any(re.search(r"process started with pid \[\d+\]", line) for line in crash)
        assert any(re.search(r"process has died \[pid \d+, exit code 3\]", line)
                   for line in crash)
        everyone = app.store.text(View())
        assert any("[crash-1] process has died" in line for line in everyone)
        await pilot.press("down", "down")  # all nodes, then the crash
        assert panel_of(app).view.process == "crash-1"
        await until(pilot, lambda: any("process has died" in r
                                       for r in panel_of(app).line_view.visible_text()))
        detail = str(app.query_one("#detail").render())
        assert "failed" in detail and "exit code 3" in detail
        await pilot.press("down")
        await until(pilot, lambda: "not found" in str(app.query_one("#detail").render()))
        assert any("failed:" in line for line in app.store.text(View("absent-2")))
        await pilot.press("down", "s")  # the operator stops `fine`: a stop, not a death
        await until(pilot, lambda: any("process stopped [pid" in line
                                       for line in app.store.text(View("fine-3"))))
        assert not any("process has died" in line for line in app.store.text(View("fine-3")))
        assert "failed" not in row_text(app, "fine-3")


async def test_action_rows_never_read_pid_none(tmp_path):
    async with tui(tmp_path, "robot:=tuia", "listener:=false") as (app, pilot):
        await until(pilot, lambda: states(app).get("set_parameters-1") == "done")
        await until(pilot, lambda: "done" in row_text(app, "set_parameters-1"))
        assert "pid None" not in row_text(app, "set_parameters-1")


# --- 7. tab keys from fields --------------------------------------------------------------


async def test_escape_leaves_any_field_and_digits_then_switch_tabs(tmp_path):
    async with tui(tmp_path, "robot:=tuit", "services:=false", size=(80, 24)) as (app, pilot):
        await pilot.press("2")
        field = app.query_one("#arg-rate", Field)
        field.focus()
        await pilot.pause()
        burst(app, "end", "1")
        await until(pilot, lambda: field.value == "2.01")
        assert app.tabs.active == "args"  # a digit is typed
        field.value = "2.0"
        burst(app, "escape", "3")
        await until(pilot, lambda: app.tabs.active == "services")
        assert field.value == "2.0"
        # the tab shows its list, not a text field: the tab keys and q work at once
        assert app.focused is app.query_one("#svc-list")
        burst(app, "escape", "4")
        await until(pilot, lambda: app.tabs.active == "params")
        burst(app, "escape", "1")
        await until(pilot, lambda: app.tabs.active == "nodes")
        assert isinstance(app.focused, LaunchTree), app.focused
        await pilot.press("slash", *"abc")
        burst(app, "escape", "2")
        await until(pilot, lambda: app.tabs.active == "args")
        assert panel_of(app).search == ""


# --- 8. follow ----------------------------------------------------------------------------


async def test_follow_holds_across_node_switches_resizes_and_a_cancelled_search(tmp_path):
    async with tui(tmp_path, "robot:=tuif", "services:=false", "rate:=10",
                   size=(80, 24)) as (app, pilot):
        panel = panel_of(app)
        await until(pilot, lambda: len(app.store.lines(View("talker-1"))) > 40)
        view = panel.line_view

        def at_newest() -> bool:
            return view.visible_text()[-1].endswith(view.lines[-1].message)

        await pilot.press("down", "down", "down")  # talker
        assert view.following and panel.unseen == 0
        await until(pilot, at_newest)
        await pilot.press("up", "up")  # all nodes
        assert view.following and panel.unseen == 0
        await until(pilot, at_newest)
        await pilot.press("slash", "escape")
        assert view.following
        await pilot.resize_terminal(100, 30)
        await pilot.pause(1.2)
        assert view.following and panel.unseen == 0
        await until(pilot, at_newest)
        # scrolled up: exact count of what arrived below, "1 new line" singular
        view.focus()
        await pilot.press("pageup")
        assert not view.following
        await until(pilot, lambda: panel.unseen > 0)
        await pilot.press("G")
        assert view.following and panel.unseen == 0


# --- 9. group restart re-runs its actions; root stop asks ------------------------------------


async def test_restarting_a_group_reruns_its_set_parameters(tmp_path):
    async with tui(tmp_path, "robot:=tuig", "services:=false", "listener:=false",
                   "mode:=dock") as (app, pilot):
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


async def test_stop_on_the_root_asks_first(tmp_path):
    async with tui(tmp_path, "robot:=tuis", "services:=false") as (app, pilot):
        await until(pilot, lambda: len(pids(app)) >= 3)
        app.query_one(LaunchTree).focus()
        await pilot.press("home")  # the root row
        await pilot.press("s")
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("n")
        await pilot.pause(0.3)
        assert len(pids(app)) >= 3
        await pilot.press("s", "y")
        await until(pilot, lambda: not pids(app))


# --- 10. params "launch file" column for nodes named by their code --------------------------


async def test_params_launch_column_matches_a_node_by_the_name_it_reports(tmp_path):
    async with tui(tmp_path, "robot:=tuip", "services:=false", "listener:=false") \
            as (app, pilot):
        # configurable has no name in the launch file (plan full_name is None)
        assert app.session.plan.process("configurable-3").full_name is None
        await until(pilot, lambda: states(app).get("set_parameters-1") == "done")
        panel = await tab_panel(pilot, app, "4", ParamsPanel)
        await until(pilot, lambda: "/tuip/control/configurable" in panel.nodes,
                    every=panel.refresh_listing)
        panel.load_node("/tuip/control/configurable")
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


async def test_descriptions_keep_brackets_and_the_current_match_stands_out(tmp_path):
    async with tui(tmp_path, "robot:=tuim", "services:=false", "rate:=20") as (app, pilot):
        await pilot.press("2")
        helps = [str(s.render()) for s in app.query(".arg-help")]
        assert any("talker publishing rate [Hz]" in h for h in helps)
        await pilot.press("escape", "1")
        await until(pilot, lambda: len(app.store.lines(View("talker-1"))) > 10)
        await pilot.press("down", "down", "down", "slash", *"says", "enter")
        view = panel_of(app).line_view
        assert view.current_match is not None
        current = view._text(view.current_match)
        other = view._text(view.matches()[0] if view.matches()[0] != view.current_match
                           else view.matches()[1])
        assert any("yellow" in str(span.style) for span in current.spans)
        assert not any("yellow" in str(span.style) for span in other.spans)


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


def test_a_linux_console_gets_ascii_state_icons(monkeypatch, write, tmp_path):
    import asyncio

    monkeypatch.setenv("TERM", "linux")

    async def scenario() -> None:
        async with launched(str(write(QUIET)), {}, tmp_path, (80, 24)) as (app, pilot):
            await until(pilot, lambda: "running" in row_text(app, "quiet-1"))
            label = row_text(app, "quiet-1")
            assert label.startswith("* ") and "●" not in label

    asyncio.run(scenario())


GATED = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    code = ('import os, sys, time\\n'
            'for i in range(31):\\n'
            '    print(f"[INFO] [0.0] [counter]: line {{i}}", flush=True)\\n'
            'while not os.path.exists("{gate}"):\\n'
            '    time.sleep(0.05)\\n'
            'print("[INFO] [0.0] [counter]: line 31", flush=True)\\n'
            'time.sleep(600)\\n')
    return LaunchDescription([ExecuteProcess(name='counter0', cmd=[{python!r}, '-c', code])])
"""


async def test_focus_shows_in_reverse_video_and_one_new_line_is_singular(write, tmp_path):
    # the next line comes when the test says so: what the status counts is never a race
    gate = tmp_path / "more"
    path = write(GATED.format(gate=str(gate), python=sys.executable), "gated.py")
    async with launched(str(path), {}, tmp_path, (80, 24)) as (app, pilot):
        tree = app.query_one(LaunchTree)
        await pilot.pause()
        # the focused tree's cursor row is drawn in reverse video: visible with 8 colours
        assert any(seg.style is not None and seg.style.reverse
                   for seg in tree.render_line(0)._segments)
        await pilot.press("down", "down")
        await until(pilot, lambda: last_number(app) >= 30)
        view = panel_of(app).line_view
        view.focus()
        await pilot.press("up")  # one line up: the newest is just below the pane
        assert not view.following
        status = app.query_one("#output-status")
        assert "1 new line (G: follow)" in str(status.render())
        gate.touch()  # one more arrives below
        await until(pilot, lambda: "2 new lines (G: follow)" in str(status.render()))


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
        read_for(master, 0.3)
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
        read_for(master, 0.3)
        os.write(master, b"y\x1bq")  # type y, then escape and q together: leave, then quit
        screen = read_until(master, b"and quit?")
        assert b"yq" not in screen  # the q was not typed into the field
