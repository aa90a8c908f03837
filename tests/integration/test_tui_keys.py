"""Keys go where they are typed: a burst read in one go (over ssh, pasted, sent by tmux)
after a key that opens a field reaches that field, in order, and never the tree's keys
(`s` stops a node); the focus is always somewhere visible; dialogs do not stack."""

from __future__ import annotations

import json
import os
import re
import sys
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

import pytest
from textual import events
from textual.widgets import Input

from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.fields import Field

from .test_interact import PROGRAMS
from .test_sessions import runtime  # noqa: F401  (a fixture: a private session folder)
from .test_tui import launched, pids, until
from .test_tui_long_sessions import read_for, read_until, start_on_pty, stop_pty

TWO = f"""
import sys
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
PROGRAMS = {str(PROGRAMS)!r}
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('robot', default_value='r1', description='the robot'),
        ExecuteProcess(name='lines', cmd=[sys.executable, PROGRAMS + '/line_reader.py'],
                       output='screen', emulate_tty=True),
        ExecuteProcess(name='quiet', cmd=['sleep', '600']),
    ])
"""


def palette_input(app: Any) -> str | None:
    """What the command palette's input holds; None before the palette has laid it out
    (pushed, not yet composed, on a loaded machine)."""
    found = app.screen.query("CommandInput")
    return str(found.first().value) if found else None


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


@asynccontextmanager
async def two_started(write, tmp_path) -> AsyncIterator[tuple[TuiLaunchApp, Any, dict[str, int]]]:
    """The TUI of TWO at 80x24, both processes started and quiet-2 selected: the app, its
    pilot and the processes' pids; the launch is shut down afterwards."""
    async with launched(str(write(TWO)), {}, tmp_path, (80, 24)) as (app, pilot):
        yield app, pilot, await started(app, pilot)


async def test_a_search_typed_in_one_burst_is_searched_and_never_stops_the_node(write,
                                                                               tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, before):
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


async def test_keys_after_i_reach_the_node_in_order(write, tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, before):
        select(app, "lines-1")
        await pilot.pause()
        # i, then a line with s, r, t, q and a digit in it, Enter: one read
        burst(app, "i", *"start 1 q", "enter")
        await until(pilot, lambda: "got: start 1 q" in pane(app, "lines-1"))
        assert app.keyboard.typing_to == "lines-1" and not app.quitting
        assert pids(app) == before
        burst(app, "ctrl+right_square_bracket", "q")  # the keys are back: q asks to quit
        await until(pilot, lambda: type(app.screen).__name__ == "QuitScreen")
        burst(app, "n")
        await until(pilot, lambda: type(app.screen).__name__ != "QuitScreen")


async def test_the_palette_and_a_field_opened_by_a_tab_key_get_the_burst(write, tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, before):
        # ctrl+p and a command's words in one read: the words are in the palette's input
        burst(app, "ctrl+p", *"stop")
        await until(pilot, lambda: type(app.screen).__name__ == "CommandPalette")
        await until(pilot, lambda: palette_input(app) == "stop")
        burst(app, "escape")
        await until(pilot, lambda: type(app.screen).__name__ != "CommandPalette")
        # `:` opens the palette too (as in vim, k9s)
        burst(app, "colon", *"rst")
        await until(pilot, lambda: type(app.screen).__name__ == "CommandPalette")
        await until(pilot, lambda: palette_input(app) == "rst")
        burst(app, "escape")
        await until(pilot, lambda: type(app.screen).__name__ != "CommandPalette")
        # the Topics tab and its filter, in one read with the text
        burst(app, "5", "slash", *"chat")
        await until(pilot, lambda: field(app, "tpc-filter").value == "chat")
        assert pids(app) == before


async def test_a_value_typed_after_the_args_tab_key_in_one_read_goes_into_its_field(
        write, tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, before):
        # the Args tab, one tab past Apply and Defaults into the robot's field, its value
        # replaced: one read
        burst(app, "2", "tab", "ctrl+u", *"r2sq")
        await until(pilot, lambda: field(app, "arg-robot").value == "r2sq")
        assert not app.quitting and pids(app) == before
        await until(pilot, lambda: app.args_tab.preview is not None
                    and app.args_tab.preview.arguments.get("robot") == "r2sq")
        # back to Apply (shift+tab from the first value), right to Defaults: a space there
        # resets nothing, Enter does
        burst(app, "shift+tab", "right", "space")
        await until(pilot, lambda: app.focused is app.query_one("#defaults"))
        await pilot.pause(0.2)
        assert field(app, "arg-robot").value == "r2sq"
        burst(app, "enter")
        await until(pilot, lambda: field(app, "arg-robot").value == "r1")


def test_a_search_written_to_a_real_terminal_in_one_write_stops_nothing(write, tmp_path):
    """The same as ssh delivers it: `/set` and enter in one write to the TUI's terminal."""
    proc, master = start_on_pty(tmp_path, str(write(TWO)))
    try:
        read_until(master, b"2 running")
        os.write(master, b"\x1b[B\x1b[B\x1b[B")  # down to quiet-2 (root, all nodes, lines)
        read_until(master, b"quiet-2  ")
        os.write(master, b"/set\r")
        read_until(master, b"/set no line matches")
        os.write(master, b"q")  # the question counts what still runs: both
        read_until(master, b"2 processes still run")
    finally:
        stop_pty(proc, master)


# --- focus and dialogs: the habits of a keyboard user -------------------------------------


def dialogs(app: TuiLaunchApp) -> list[str]:
    return [type(screen).__name__ for screen in app.screen_stack[1:]]


async def test_ctrl_c_twice_asks_once_and_n_leaves_no_question(write, tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, before):
        burst(app, "ctrl+c", "ctrl+c")
        await until(pilot, lambda: dialogs(app) == ["QuitScreen"])
        burst(app, "q", "ctrl+c")
        await pilot.pause(0.3)
        assert dialogs(app) == ["QuitScreen"]
        burst(app, "n")
        await until(pilot, lambda: dialogs(app) == [])
        assert pids(app) == before


async def test_tab_keys_and_q_work_from_every_tab_and_the_focus_is_never_a_field(write,
                                                                               tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, _):
        for key, tab in (("2", "args"), ("3", "services"), ("4", "params"), ("5", "topics"),
                         ("1", "nodes")):
            burst(app, key, "q")  # the tab, then q at once: the quit question, nothing typed
            await until(pilot, lambda: dialogs(app) == ["QuitScreen"])
            assert app.tabs.active == tab
            burst(app, "n")
            await until(pilot, lambda: dialogs(app) == [])
            assert not isinstance(app.focused, Input), (tab, app.focused)
            assert app.focused is not None and app.focused.has_pseudo_class("focus")
        assert field(app, "arg-robot").value == "r1"  # no q, no digit typed into it
        # each tab's list has its filter one `/` away, and esc comes back to the list
        burst(app, "3", "slash", *"srv")
        await until(pilot, lambda: field(app, "svc-filter").value == "srv")
        burst(app, "escape", "q")
        await until(pilot, lambda: dialogs(app) == ["QuitScreen"])
        burst(app, "n")
        await until(pilot, lambda: dialogs(app) == [])
        assert app.focused is app.query_one("#svc-list")


async def test_leaving_the_search_goes_back_where_it_was_typed(write, tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, _):
        tree = app.launch_tree
        burst(app, "slash", *"abc", "escape")  # from the tree: back to the tree
        await until(pilot, lambda: app.focused is tree)
        burst(app, "backslash", *"ready", "enter")
        await until(pilot, lambda: app.output_panel.view.text == "ready")
        assert app.focused is tree
        lines = app.output_panel.line_view
        app.screen.set_focus(lines)
        burst(app, "slash", *"x", "enter")  # from the pane: back to the pane
        await until(pilot, lambda: app.output_panel.search == "x")
        assert app.focused is lines


async def test_f1_and_the_palettes_keys_show_the_keys_and_esc_closes_them(write, tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, _):
        burst(app, "f1")
        await until(pilot, lambda: dialogs(app) == ["HelpScreen"])
        burst(app, "escape")
        await until(pilot, lambda: dialogs(app) == [])
        burst(app, "ctrl+p", *"keys")
        await until(pilot, lambda: dialogs(app) == ["CommandPalette"]
                    and palette_input(app) == "keys")
        await until(pilot, lambda: "Keys" in str(app.screen.query_one("CommandList")
                                                  .get_option_at_index(0).prompt))
        burst(app, "enter")
        await until(pilot, lambda: dialogs(app) == ["HelpScreen"])
        assert not app.query("HelpPanel")  # not Textual's side panel (30 of 80 columns)
        burst(app, "escape")
        await until(pilot, lambda: dialogs(app) == [])


def start_on_console(tmp_path, *argv: str, term: str = "linux"):
    """The TUI on a pseudo-terminal that says it is a Linux console (or another TERM)."""
    import fcntl
    import pty
    import struct
    import subprocess
    import termios

    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path), "TERM": term}
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", *argv], stdin=slave,
                            stdout=slave, stderr=slave, env=env, start_new_session=True)
    os.close(slave)
    return proc, master


CONSOLE = """
from launch.actions import ExecuteProcess
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('loud', True, description='talk')
    sl.declare_arg('quiet', False, description='listen')
    sl.add_action(ExecuteProcess(name='quiet', cmd=['sleep', '600']))
    return sl.launch_description()
"""


@pytest.mark.usefixtures("runtime")
def test_a_linux_console_gets_ascii_lines_and_a_checkbox_that_reads_its_value(write,
                                                                               tmp_path):
    proc, master = start_on_console(tmp_path, str(write(CONSOLE)))
    try:
        screen = read_until(master, b"1 running")
        os.write(master, b"2")
        screen += read_until(master, b"listen")
        os.write(master, b"3")
        screen += read_until(master, b"services")
        os.write(master, b"q")
        screen += read_until(master, b"and quit?")
        # the characters drawn, without the colour changes between them
        text = re.sub(r"\x1b\[[0-9;]*m", "", screen.decode("utf-8", "replace"))
        drawn = [glyph for glyph in "▎▊▔▁╸╺━├└│╭╮╰╯▐▌" if glyph in text]
        assert not drawn, drawn
        assert "[X]" in text and "[ ]" in text  # true and false read apart
    finally:
        stop_pty(proc, master)


@pytest.mark.usefixtures("runtime")
def test_quitting_a_session_offers_detach_and_d_leaves_it_running(write, tmp_path):
    from .test_sessions import tl

    proc, master = start_on_console(tmp_path, str(write(CONSOLE)), term="xterm-256color")
    try:
        read_until(master, b"1 running")
        os.write(master, b"q")
        read_until(master, b"Or detach")
        os.write(master, b"d")
        end = time.monotonic() + 60
        while proc.poll() is None:  # the window closes (what it writes is read) ...
            assert time.monotonic() < end, "the TUI did not leave after d"
            read_for(master, 0.2)
        (session,) = json.loads(tl("ls", "--json").stdout)  # ... and the launch runs on
        name = session["name"]
        assert '"running"' in tl("status", name, "--json").stdout
        tl("stop", name)
    finally:
        stop_pty(proc, master)


async def test_a_paste_right_after_slash_is_searched(write, tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, before):
        burst(app, "slash")  # `/`, then a bracketed paste, in one read
        app.post_message(events.Paste("start"))
        burst(app, "enter")
        await until(pilot, lambda: app.output_panel.search == "start")
        assert pids(app) == before


def test_escape_and_a_backslash_in_one_write_leave_the_search_and_open_the_filter(write,
                                                                                   tmp_path):
    """A terminal sends ESC then `\\` typed fast as one read, which Textual alone reads as
    `\\` (the escape lost): it must leave the search, then open the text filter."""
    proc, master = start_on_pty(tmp_path, str(write(TWO)))
    try:
        read_until(master, b"2 running")
        os.write(master, b"/abc")
        read_until(master, b"abc")
        os.write(master, b"\x1b\\ready\r")
        read_until(master, b"only 'ready'")
    finally:
        stop_pty(proc, master)


async def test_the_footer_does_not_offer_keys_a_field_types(write, tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, _):
        offered = {b.binding.description for b in app.screen.active_bindings.values()
                   if b.binding.show}
        assert {"Search", "Filter"} <= offered  # in the tree: / and \ are commands
        burst(app, "slash")
        await until(pilot, lambda: app.focused is field(app, "search-input"))
        offered = {b.binding.description for b in app.screen.active_bindings.values()
                   if b.binding.show}
        assert not {"Search", "Filter", "Level", "Quit"} & offered  # typed into the field


async def test_c_then_y_in_one_read_copies_the_command_line(write, tmp_path):
    async with two_started(write, tmp_path) as (app, pilot, _):
        select(app, "lines-1")
        await pilot.pause()
        burst(app, "c", "y")  # the dialog comes after a round trip: y waits for it
        await until(pilot, lambda: "line_reader.py" in app.clipboard)
        await until(pilot, lambda: dialogs(app) == [])  # y copied and closed it
