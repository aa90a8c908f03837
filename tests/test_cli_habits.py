"""The command line's habits (issue 26, item 8) that no other test file holds, each tried as
a user tries it: real launches, the command run as a shell runs it."""

from __future__ import annotations

import os
import signal

from tuilaunch.engine.run.session import session_dir

from .conftest import wait_for
from .test_sessions import Terminal
from .test_sessions import runtime as runtime  # the private session folder

TALKER = """
from launch import LaunchDescription
from launch_ros.actions import Node
def generate_launch_description():
    return LaunchDescription([Node(package='tuilaunch_demos', executable='talker',
                                   name='talker', parameters=[{'rate': 5.0}])])
"""


def test_a_foreground_tui_closed_by_sighup_leaves_no_parameter_folder(runtime, write,
                                                                       tmp_path, monkeypatch):
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setenv("TMPDIR", str(tmp))
    terminal = Terminal(str(write(TALKER)))
    try:
        terminal.read_until(b"1 running")
        # the TUI's plan and the server's each wrote the node's parameters
        assert len(list(tmp.glob("tuilaunch-*-params-*"))) == 2
        os.kill(terminal.proc.pid, signal.SIGHUP)  # the ssh link or the tmux pane is gone
        terminal.wait_exit()
    finally:
        terminal.close()
    wait_for(lambda: not session_dir.live_sessions(), what="the launch stopped")
    wait_for(lambda: not list(tmp.glob("tuilaunch-*")),
             what=f"no folder left in $TMPDIR: {list(tmp.iterdir())}")
