"""A recording over ssh: `tuilaunch record HOST:NAME` through a real sshd on 127.0.0.1
(tests/integration/sshd.py) records where the publisher runs and writes the file on this
computer, every message as published."""

from __future__ import annotations

import sys
from pathlib import Path

from ..conftest import run_cli
from .session_steps import start_here, stop_here
from .sshd import Machines, machines_fixture  # noqa: F401
from .test_record import read
from .test_remote_sessions import logged_in  # a user's environment on that machine
from .test_sessions import wait_state

SIGNAL_NODE = Path(__file__).resolve().parent / "nodes" / "signal_node.py"
LAUNCH = f"""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='wave', cmd=[
        {sys.executable!r}, {str(SIGNAL_NODE)!r}, 'ssh_rec', '--topic', '/ssh/rec',
        '--rate', '50'])])
"""


def test_a_recording_over_ssh_is_written_here(machines: Machines, write, tmp_path):
    robot = machines["robot1"]
    with logged_in(robot):  # the setting, from this process: the recording is the subject
        start_here(write(LAUNCH), "--name", "farrec")
    out = tmp_path / "here" / "far.mcap"
    out.parent.mkdir()
    try:
        with logged_in(robot):
            wait_state("farrec", "wave-1", "running")
        # 10 s: on a loaded machine the link and the subscription's discovery take seconds
        # of it before the first message (one run got 50 messages of a 4 s recording)
        recorded = run_cli("record", "robot1:farrec", "/ssh/rec", "-o", str(out),
                           "--duration", "10")
        assert recorded.returncode == 0, recorded.stderr
        again = run_cli("record", "robot1:farrec", "/ssh/rec", "-o", str(out),
                        "--duration", "1")
        assert again.returncode != 0 and "Traceback" not in again.stderr
        assert f"{out} exists: tuilaunch never overwrites a recording" in again.stderr
    finally:
        with logged_in(robot):
            stop_here("farrec", gone_ok=True)
    _, messages = read(out)
    numbers = [int(m.z) for topic, _, m in messages if topic == "/ssh/rec"]
    assert len(numbers) > 50
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers)))
    assert not list((robot.folder / "roslog").rglob("*.mcap"))  # nothing written there
