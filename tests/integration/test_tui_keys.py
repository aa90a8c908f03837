"""Keys written to a real terminal: a burst read in one go (over ssh, pasted, sent by tmux)
reaches the field it opens and never the tree's keys (`s` stops a node), esc and a key
typed fast are both read; a Linux console gets ASCII lines; `q` offers to detach and `d`
leaves the launch running.

The App's own side of bursts, focus and dialogs (posted keys, over an in-memory session)
is tested in tests/unit/test_app_key_bursts.py."""

from __future__ import annotations

import json
import os
import re
import sys
import time

import pytest
from textual import events

from tuilaunch.tui.app import TuiLaunchApp

from .session_steps import stop_here
from .test_interact import PROGRAMS
from .test_sessions import runtime  # noqa: F401  (a fixture: a private session folder)
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


def burst(app: TuiLaunchApp, *keys: str) -> None:
    """Keys as one read from the terminal delivers them: posted together, nothing run in
    between (Pilot.press waits after each key, which hides ordering faults)."""
    for key in keys:
        char = key if len(key) == 1 else {"slash": "/", "backslash": "\\",
                                           "colon": ":", "space": " "}.get(key)
        app.post_message(events.Key(key, char))


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
        stop_here(name)
    finally:
        stop_pty(proc, master)


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


