"""The output panes as a user reads them, against real processes: tabs line up as in a
terminal, a scrolled-back view holds still under a flood, a respawn called off, typing into
a node that prompts without a newline, long lines kept whole.

The pane's habits over a given stream of lines (an empty result, Esc, a group's stop said)
are tested over an in-memory session in tests/unit/test_app_output_habits.py, and a long
failure reason read whole at 80 columns in tests/unit/test_app_tree.py."""

from __future__ import annotations

import re

from tuilaunch.tui.app import TuiLaunchApp, make_app
from tuilaunch.tui.screens.output_panel import OutputPanel

from .session_steps import stop_here
from .terminal_harness import PROGRAMS
from .test_sessions import detached_with, runtime, tl  # noqa: F401  (runtime: a fixture)
from .test_tui import launched, until

LAUNCH = f"""
import sys
from launch import LaunchDescription
from launch.actions import ExecuteProcess
PROGRAMS = {str(PROGRAMS)!r}
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name=name, cmd=[sys.executable, PROGRAMS + '/' + name + '.py', *args],
                       output='screen', emulate_tty=True)
        for name, args in {{programs}}])
"""


def launch(write, *programs: tuple[str, list[str]]) -> str:
    return str(write(LAUNCH.replace("{programs}", repr(list(programs)))))


def panel_of(app: TuiLaunchApp) -> OutputPanel:
    return app.query_one(OutputPanel)


def rows(app: TuiLaunchApp) -> list[str]:
    """The pane's rows as the user reads them, to the last one written."""
    shown = panel_of(app).line_view.visible_text()
    while shown and not shown[-1]:
        shown.pop()
    return shown


async def select(app: TuiLaunchApp, pilot, process: str) -> None:
    """The process's row selected, its pane shown; selected again should the tree be drawn
    anew meanwhile (its rows come with the plan the session's server sends)."""
    tree = app.launch_tree

    def on_its_row() -> bool:
        node = tree.rows.get(process)
        if node is not None and tree.cursor_node is not node:
            tree.move_cursor(node)
        return panel_of(app).view.process == process

    await until(pilot, on_its_row)


# --- tabs ---------------------------------------------------------------------------------


async def test_tabs_line_up_at_8_columns_as_in_a_terminal(write, tmp_path):
    path = launch(write, ("tab_printer", []))
    async with launched(path, {}, tmp_path, (120, 24)) as (app, pilot):
        await select(app, pilot, "tab_printer-1")
        await until(pilot, lambda: any("end" in r for r in rows(app)))
        shown = [r.split(" ", 1)[1] for r in rows(app) if r.startswith("I ")]
        # each cell starts on the column a terminal's 8-column tab stops put it
        assert shown == [
            "120     ../sysdeps/unix/sysv/linux/nanosleep.c: No such file or directory.",
            "PID     TTY     TIME    CMD",
            "1       pts/0   00:00:01        bash",
            "12345678        pts/12  00:00:00        ps",
            "ab      cd      end",
        ]
        # the log file keeps the line as it was printed
        log = next((tmp_path / "log").rglob("tab_printer-1*.log")).read_text()
        assert "120\t../sysdeps/" in log


def test_a_wide_character_takes_two_columns_before_a_tab():
    from tuilaunch.engine.run.vocabulary.text import expand_tabs

    assert expand_tabs("日本\tx") == "日本    x"  # 4 columns of text, 4 of spaces
    assert expand_tabs("e\u0301\tx") == "e\u0301       x"  # a combining accent takes none


# --- a scrolled-back view under a flood --------------------------------------------------


def number_of(row: str) -> int:
    return int(row.split("line ", 1)[1].split()[0])


async def test_a_scrolled_back_view_holds_still_under_a_flood_until_g(write, tmp_path):
    # ~2,000 lines a second into a 500-line scrollback: trimmed several times a second
    path = launch(write, ("flooder", ["2000"]))
    async with launched(path, {}, tmp_path, (80, 24), scrollback=500) as (app, pilot):
        await select(app, pilot, "flooder-1")
        panel = panel_of(app)
        view = panel.line_view
        await until(pilot, lambda: len(view.lines) == 500)
        view.focus()
        await pilot.press("pageup")
        assert not view.following
        await pilot.pause()
        held = rows(app)
        assert all("line " in r for r in held)
        # more than two scrollbacks' worth arrive below: what the user reads stays
        await until(pilot, lambda: panel.unseen > 1200)
        arrived = panel.unseen
        await until(pilot, lambda: panel.unseen > arrived + 500)  # past a repaint or two
        assert rows(app) == held
        status = str(panel._status.render())
        assert " new" in status and "(G" in status
        assert len(status) <= panel._status.size.width  # fits the pane at 80 columns

        # a search over what is held: its matches neither come nor go
        await pilot.press("slash", *"00 of", "enter")
        await until(pilot, lambda: "/00 of 1/" in str(panel._status.render()))
        status = str(panel._status.render())
        assert len(status) <= panel._status.size.width  # shortened, not cut
        count = status.split("/00 of 1/", 1)[1].split()[0]
        on_screen = [r for r in rows(app) if "00 of" in r]
        assert on_screen
        for step in range(2, 5):
            await pilot.press("n")
            await until(pilot, lambda step=step: f"/00 of {step}/{count}"
                        in str(panel._status.render()))
        # down past the last held line: what came meanwhile follows on, after a line
        # saying how many did not fit aside
        await pilot.press("escape")
        view.focus()
        for _ in range(60):
            if any("lines here are only in the log file" in r for r in rows(app)):
                break
            await pilot.press("pagedown")
        for _ in range(30):  # line by line until the marker is in the upper half
            shown = rows(app)
            gap = next(i for i, r in enumerate(shown) if "only in the log file" in r)
            if gap < 10:
                break
            await pilot.press("down")
        assert shown[gap].startswith("-- ")
        after = [number_of(r) for r in shown[gap + 1:]]
        assert after == list(range(after[0], after[0] + len(after)))  # none missing
        assert not view.following
        await pilot.press("end")
        assert view.following
        await until(pilot, lambda: number_of(rows(app)[-1]) > number_of(held[-1]) + 1200)
        # down at the newest line keeps following
        newest = number_of(rows(app)[-1])
        await pilot.press("down", "down")
        assert view.following
        await until(pilot, lambda: number_of(rows(app)[-1]) > newest)


# --- a respawn called off -----------------------------------------------------------------


async def test_s_on_a_node_waiting_to_respawn_keeps_it_down(write, tmp_path):
    path = write("""
        from launch import LaunchDescription
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            return LaunchDescription([
                ExecuteProcess(name='oneshot', respawn=True, respawn_delay=600.0,
                               cmd=['sh', '-c', 'echo once; exit 0'])])
        """)
    async with launched(str(path), {}, tmp_path, (80, 24)) as (app, pilot):
        await select(app, pilot, "oneshot-1")
        detail = app.query_one("#detail")
        # counted down from 600 s
        await until(pilot, lambda: re.search(r"respawning \(try 1 in (600|59\d) s\)",
                                             str(detail.render())) is not None)
        await pilot.press("s")
        await until(pilot, lambda: "oneshot-1 (/oneshot): exited" in str(detail.render()))
        await until(pilot, lambda: any("respawn called off" in line for line in rows(app)))
        assert "try 1" not in str(detail.render())


# --- typing into a node --------------------------------------------------------------------


def footer_keys(app: TuiLaunchApp) -> list[str]:
    """The footer as the user reads it: `key description` for each key it offers."""
    return [f"{key.key_display} {key.description}" for key in app.query("FooterKey")
            if not key.disabled]


async def test_typing_into_a_prompt_without_a_newline(write, tmp_path):
    path = launch(write, ("prompt_reader", []))
    async with launched(path, {}, tmp_path, (80, 24)) as (app, pilot):
        await select(app, pilot, "prompt_reader-1")
        # gdb's `(gdb) ` waits without a newline: shown as it stands, before any Enter
        await until(pilot, lambda: rows(app)[-2:] == ["I ready", "I (gdb)"])
        await pilot.press("i")
        await until(pilot, lambda: app.keyboard.typing_to == "prompt_reader-1")
        await until(pilot, lambda: footer_keys(app) == ["ctrl+] Give the keys back"])
        # the terminal's echo shows as it comes; a backspace erases, it leaves no space
        await pilot.press(*"abc", "backspace")
        await until(pilot, lambda: rows(app)[-1] == "I (gdb) ab")
        await pilot.press("enter")
        await until(pilot, lambda: "I answer: ab" in rows(app))
        texts = [line.text for line in panel_of(app).line_view.lines]
        assert texts[-2:] == ["(gdb) ab", "answer: ab"]
        await until(pilot, lambda: rows(app)[-1] == "I (gdb)")  # the next prompt
        # a ctrl+c typed into it ends it: the operator's doing, not a failure
        await pilot.press("ctrl+c")
        await until(pilot, lambda: any("process stopped by a key typed into it" in r
                                       for r in rows(app)))
        assert app.supervisor is not None
        assert app.supervisor.states["prompt_reader-1"] == "exited"
        assert app.launch_tree.states["prompt_reader-1"] == "exited"
        assert "failed" not in str(app.status_bar.render())
        await until(pilot, lambda: app.keyboard.typing_to is None)
        await until(pilot, lambda: "ctrl+] Give the keys back" not in footer_keys(app)
                    and any("Stop" in key for key in footer_keys(app)))


def test_a_client_attaching_to_a_session_sees_the_waiting_prompt(write, runtime):  # noqa: F811
    import asyncio

    path = launch(write, ("prompt_reader", []))
    name, log_dir = detached_with(path, "prompt_reader-1")

    async def scenario() -> None:
        # attached after the prompt was printed: the log file has only `ready`
        app = make_app(path, {}, log_dir, session_name=name)
        async with app.run_test(size=(80, 24)) as pilot:
            await select(app, pilot, "prompt_reader-1")
            await until(pilot, lambda: rows(app)[-2:] == ["I ready", "I (gdb)"])
            await pilot.press("i")
            await until(pilot, lambda: app.keyboard.typing_to == "prompt_reader-1")
            await pilot.press(*"bt", "enter")
            await until(pilot, lambda: rows(app)[-3:] == ["I (gdb) bt", "I answer: bt",
                                                         "I (gdb)"])
            await pilot.press("ctrl+right_square_bracket")
            await pilot.press("d")
            await until(pilot, lambda: getattr(app.supervisor, "detached", False))

    asyncio.run(scenario())
    stop_here(name)


# --- long lines -----------------------------------------------------------------------------

LONG = 1 << 20
LONG_LINE = "<<" + ("0123456789" * (LONG // 10 + 1))[:LONG - 4] + ">>"  # long_line.py's


def test_a_1_mib_line_is_kept_whole_in_the_log_logs_and_the_pane(write, runtime):  # noqa: F811
    """A robot description or a message dumped on one line: written 4 KB at a time, it was
    cut into 64 KB lines everywhere. Now it is one line in the log file, in `tuilaunch
    logs`, and in the pane of a TUI attached over the session's socket, whose `w` saves it
    whole; the pane draws the start of it on its row."""
    import asyncio
    import time

    path = launch(write, ("long_line", []))
    name, log_dir = detached_with(path, "long_line-1")
    try:
        log = log_dir / "long_line-1.log"
        deadline = time.monotonic() + 60
        while b" after" not in log.read_bytes()[-100:] and time.monotonic() < deadline:
            time.sleep(0.05)
        logged = [line.split(b" ", 2)[2].rstrip(b"\r") for line in log.read_bytes().splitlines()]
        assert logged == [b"before", LONG_LINE.encode(), b"after"]

        printed = tl("logs", name, "long_line-1").stdout.splitlines()
        assert [line for line in printed if line.strip()][-3:] == \
            ["before", LONG_LINE, "after"], [line[:80] for line in printed]

        async def scenario() -> None:
            app = make_app(path, {}, log_dir, session_name=name)
            async with app.run_test(size=(80, 24)) as pilot:
                await select(app, pilot, "long_line-1")
                await until(pilot, lambda: "I after" in rows(app))
                shown = rows(app)
                assert shown[-3] == "I before" and shown[-2].startswith("I <<0123456789")
                assert len(shown[-2]) < 80  # drawn on its row, not wrapped over the pane
                panel = panel_of(app)
                assert panel.pane_lines()[-3:] == ["before", LONG_LINE, "after"]
                await pilot.press("w")
                await until(pilot, lambda: any(panel.save_dir.glob("long_line-1-pane-*")))
                saved = next(panel.save_dir.glob("long_line-1-pane-*")).read_text()
                assert saved.splitlines()[-3:] == ["before", LONG_LINE, "after"]

        asyncio.run(scenario())
    finally:
        stop_here(name)


def test_a_line_without_end_is_cut_at_8_mib_and_the_rest_kept(write):
    """Memory stays bounded for a process that never ends its line: past MAX_LINE (8 MiB)
    the line is cut into pieces of that size, and every byte is kept."""
    from tuilaunch.engine.run.process.output import MAX_LINE

    total = 2 * MAX_LINE + 1000
    path = write(f"""
import sys
from launch import LaunchDescription
from launch.actions import ExecuteProcess
PROGRAM = ("import sys, os\\n"
           "for _ in range({total} // 65536): os.write(1, b'x' * 65536)\\n"
           "os.write(1, b'x' * ({total} % 65536) + b'\\\\nend\\\\n')\\n")
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='endless', output='screen',
                                             cmd=[sys.executable, '-c', PROGRAM])])
""")
    from ..conftest import run_headless

    out = run_headless(path, until=("[endless-1] end",))
    lengths = [len(line) - len("[endless-1] ") for line in out.splitlines()
               if line.startswith("[endless-1] x")]
    assert lengths == [MAX_LINE, MAX_LINE, 1000], lengths
