"""Keys go where they are typed: a burst read in one go (over ssh, pasted, sent by tmux)
after a key that opens a field reaches that field, in order, and never the tree's keys
(`s` stops a node); the focus is always somewhere visible; dialogs do not stack."""

from __future__ import annotations

import os

from textual import events

from tuilaunch.tui.app import TuiLaunchApp, make_app
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.fields import Field

from .test_interact import PROGRAMS
from .test_tui import pids, until
from .test_tui_long_sessions import read_until, start_on_pty, stop_pty

TWO = f"""
import sys
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
PROGRAMS = {str(PROGRAMS)!r}
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('robot', default_value='r1', description='the robot'),
        ExecuteProcess(name='lines', cmd=[sys.executable, PROGRAMS + '/line_reader.py'],
                       output='screen'),
        ExecuteProcess(name='quiet', cmd=['sleep', '600']),
    ])
"""


def burst(app: TuiLaunchApp, *keys: str) -> None:
    """Keys as one read from the terminal delivers them: posted together, nothing run in
    between (Pilot.press waits after each key, which hides ordering faults)."""
    for key in keys:
        char = key if len(key) == 1 else {"slash": "/", "backslash": "\\",
                                           "colon": ":", "space": " "}.get(key)
        app.post_message(events.Key(key, char))


def field(app: TuiLaunchApp, field_id: str) -> Field:
    return app.query_one(f"#{field_id}", Field)


def select(app: TuiLaunchApp, process: str) -> None:
    tree = app.launch_tree
    tree.move_cursor(tree.rows[process])


def pane(app: TuiLaunchApp, process: str) -> str:
    return "\n".join(line.text for line in app.store.lines(View(process)))


async def started(app: TuiLaunchApp, pilot) -> dict[str, int]:
    await until(pilot, lambda: "ready" in pane(app, "lines-1"))
    await until(pilot, lambda: app.supervisor is not None
                and app.supervisor.states.get("quiet-2") == "running")
    select(app, "quiet-2")
    await pilot.pause()
    return pids(app)


async def shutdown(app: TuiLaunchApp) -> None:
    if app.supervisor is not None:
        await app.engine.run(app.supervisor.shutdown("test over"))


async def test_a_search_typed_in_one_burst_is_searched_and_never_stops_the_node(write,
                                                                               tmp_path):
    app = make_app(str(write(TWO)), {}, tmp_path / "log")
    async with app.run_test(size=(80, 24)) as pilot:
        before = await started(app, pilot)
        # `/set`, `/rst` and `\st` each as one read: search / filter text, no s, r, t
        burst(app, "slash", *"set")
        await until(pilot, lambda: field(app, "search-input").value == "set")
        assert app.focused is field(app, "search-input")
        burst(app, "enter", "slash", *"rst", "enter")
        await until(pilot, lambda: app.output_panel.search == "rst")
        burst(app, "backslash", *"st")
        await until(pilot, lambda: field(app, "filter-input").value == "st")
        burst(app, "escape")
        await pilot.pause()
        assert pids(app) == before  # nothing was stopped, restarted or started
        assert app.supervisor is not None
        assert app.supervisor.states["quiet-2"] == "running"
        await shutdown(app)


async def test_keys_after_i_reach_the_node_in_order(write, tmp_path):
    app = make_app(str(write(TWO)), {}, tmp_path / "log")
    async with app.run_test(size=(80, 24)) as pilot:
        before = await started(app, pilot)
        select(app, "lines-1")
        await pilot.pause()
        # i, then a line with s, r, t, q and a digit in it, Enter: one read
        burst(app, "i", *"start 1 q", "enter")
        await until(pilot, lambda: "got: start 1 q" in pane(app, "lines-1"))
        assert app.typing_to == "lines-1" and not app.quitting
        assert pids(app) == before
        burst(app, "ctrl+right_square_bracket", "q")  # the keys are back: q asks to quit
        await until(pilot, lambda: type(app.screen).__name__ == "QuitScreen")
        burst(app, "n")
        await shutdown(app)


async def test_the_palette_and_a_field_opened_by_a_tab_key_get_the_burst(write, tmp_path):
    app = make_app(str(write(TWO)), {}, tmp_path / "log")
    async with app.run_test(size=(80, 24)) as pilot:
        before = await started(app, pilot)
        # ctrl+p and a command's words in one read: the words are in the palette's input
        burst(app, "ctrl+p", *"stop")
        await until(pilot, lambda: type(app.screen).__name__ == "CommandPalette")
        await until(pilot, lambda: app.screen.query_one("CommandInput").value == "stop")
        burst(app, "escape")
        await until(pilot, lambda: type(app.screen).__name__ != "CommandPalette")
        # `:` opens the palette too (as in vim, k9s)
        burst(app, "colon", *"rst")
        await until(pilot, lambda: type(app.screen).__name__ == "CommandPalette")
        await until(pilot, lambda: app.screen.query_one("CommandInput").value == "rst")
        burst(app, "escape")
        await until(pilot, lambda: type(app.screen).__name__ != "CommandPalette")
        # the Topics tab and its filter, in one read with the text
        burst(app, "5", "slash", *"chat")
        await until(pilot, lambda: field(app, "tpc-filter").value == "chat")
        assert pids(app) == before
        await shutdown(app)


async def test_a_value_typed_after_the_args_tab_key_in_one_read_goes_into_its_field(
        write, tmp_path):
    app = make_app(str(write(TWO)), {}, tmp_path / "log")
    async with app.run_test(size=(80, 24)) as pilot:
        before = await started(app, pilot)
        # the Args tab, the robot's field, its value replaced: one read
        burst(app, "2", "ctrl+u", *"r2sq")
        await until(pilot, lambda: field(app, "arg-robot").value == "r2sq")
        assert not app.quitting and pids(app) == before
        await shutdown(app)


def test_a_search_written_to_a_real_terminal_in_one_write_stops_nothing(write, tmp_path):
    """The same as ssh delivers it: `/set` and enter in one write to the TUI's terminal."""
    proc, master = start_on_pty(tmp_path, str(write(TWO)))
    try:
        read_until(master, b"2 running")
        os.write(master, b"\x1b[B\x1b[B\x1b[B")  # down to quiet-2 (root, all nodes, lines)
        read_until(master, b"quiet-2  ")
        os.write(master, b"/set\r")
        read_until(master, b"/set no match")
        os.write(master, b"q")  # the question counts what still runs: both
        read_until(master, b"2 processes still run")
    finally:
        stop_pty(proc, master)
