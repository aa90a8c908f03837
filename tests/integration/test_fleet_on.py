"""`tuilaunch --on HOST FILE [name:=value ...]`: a launch started on another machine, over a
real sshd on 127.0.0.1 (tests/integration/sshd.py), by the tuilaunch there: its file, its
arguments and its environment are HOST's; `--detach` prints its address, without it this
terminal's TUI is attached; a host that cannot be reached, or a file that is not there, is
one line and exit 2.
"""

from __future__ import annotations

import json

from ..conftest import run_cli
from .sshd import Machines, machines_fixture  # noqa: F401
from .test_fleet_cli import with_gone_host
from .test_remote_sessions import LAUNCH
from .test_sessions import Terminal

ARGUED = LAUNCH.replace("    sl = SimpleLauncher()",
                        "    sl = SimpleLauncher()\n    sl.declare_arg('who', 'nobody')")


def test_on_host_starts_the_launch_there_detached_or_attached(machines: Machines, write):
    path = write(ARGUED, "robot.launch.py")
    started = run_cli("--on", "robot1", str(path), "who:=arm", "--detach", "--name", "far")
    assert started.returncode == 0, started.stderr
    assert started.stdout.strip() == "robot1:far"
    # a session of robot1's (its runtime folder), not of this computer's
    assert "far" not in run_cli("ls").stdout
    listed = json.loads(run_cli("ls", "robot1", "--json").stdout)
    assert [(s["name"], s["host"]) for s in listed] == [("far", "robot1")]
    assert listed[0]["arguments"] == {"who": "arm"}
    assert run_cli("wait", "robot1:far", "ticker-1", "running", "--timeout",
                   "30").returncode == 0
    # the name is taken there: the remote tuilaunch's own line, naming the host
    again = run_cli("--on", "robot1", str(path), "--detach", "--name", "far")
    assert again.returncode == 2
    assert again.stderr.splitlines()[0] == \
        "tuilaunch: error: robot1: a session named far is already running", again.stderr
    assert "Traceback" not in again.stderr

    # without --detach: the TUI attached to it, on this terminal; d leaves it running
    terminal = Terminal("--on", "robot2", str(path), "--name", "near")
    try:
        for marker in (b"robot2:near", b"tick"):
            terminal.read_until(marker, limit=90)
        assert terminal.press_until_exit(b"d") == 0
    finally:
        terminal.close()
    assert run_cli("wait", "robot2:near", "ticker-1", "running", "--timeout",
                   "30").returncode == 0
    assert run_cli("stop", "robot1:far", "robot2:near").returncode == 0


def test_on_a_host_not_reached_or_a_file_not_there_is_one_line(machines: Machines, write):
    with_gone_host(machines)
    gone = run_cli("--on", "gone", str(write(LAUNCH)), "--detach")
    assert gone.returncode == 2
    assert gone.stderr.startswith("tuilaunch: error: cannot reach gone: "), gone.stderr
    assert len(gone.stderr.strip().splitlines()) == 1, gone.stderr
    missing = run_cli("--on", "robot1", "/nowhere/robot.launch.py", "--detach")
    assert missing.returncode == 2
    first = missing.stderr.splitlines()[0]
    assert first.startswith("tuilaunch: error: robot1: ") and "robot.launch.py" in first, \
        missing.stderr
    assert "Traceback" not in missing.stderr
    bad = run_cli("--on=-oProxyCommand=x", str(write(LAUNCH)), "--detach")
    assert bad.returncode == 2 and "is not a host name" in bad.stderr
    assert json.loads(run_cli("ls", "robot1", "--json").stdout) == []
