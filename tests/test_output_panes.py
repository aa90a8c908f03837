"""The output panes as a user reads them, against real processes: tabs line up as in a
terminal, a scrolled-back view holds still under a flood, the pane's habits (follow, Esc,
an empty result, a status that fits), and typing into a node that prompts without a
newline."""

from __future__ import annotations

from tuilaunch.tui.app import TuiLaunchApp, make_app
from tuilaunch.tui.screens.output_panel import OutputPanel

from .terminal_harness import PROGRAMS
from .test_tui import until

LAUNCH = f"""
import sys
from launch import LaunchDescription
from launch.actions import ExecuteProcess
PROGRAMS = {str(PROGRAMS)!r}
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name=name, cmd=[sys.executable, PROGRAMS + '/' + name + '.py', *args],
                       output='screen')
        for name, args in {{programs}}])
"""


def launch(write, *programs: tuple[str, list[str]]) -> str:
    return str(write(LAUNCH.replace("{programs}", repr(list(programs)))))


def panel_of(app: TuiLaunchApp) -> OutputPanel:
    return app.query_one(OutputPanel)


def rows(app: TuiLaunchApp) -> list[str]:
    """The pane's rows as the user reads them."""
    return panel_of(app).line_view.visible_text()


async def select(app: TuiLaunchApp, pilot, process: str) -> None:
    tree = app.launch_tree
    await until(pilot, lambda: process in tree.rows)
    tree.move_cursor(tree.rows[process])
    await until(pilot, lambda: panel_of(app).view.process == process)


# --- tabs ---------------------------------------------------------------------------------


async def test_tabs_line_up_at_8_columns_as_in_a_terminal(write, tmp_path):
    app = make_app(launch(write, ("tab_printer", [])), {}, tmp_path / "log")
    async with app.run_test(size=(120, 24)) as pilot:
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
        assert app.supervisor is not None
        await app.engine.run(app.supervisor.shutdown("test over"))


def test_a_wide_character_takes_two_columns_before_a_tab():
    from tuilaunch.engine.run.process.output import expand_tabs

    assert expand_tabs("日本\tx") == "日本    x"  # 4 columns of text, 4 of spaces
    assert expand_tabs("e\u0301\tx") == "e\u0301       x"  # a combining accent takes none
