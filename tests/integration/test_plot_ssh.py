"""A plot over ssh: `tuilaunch plot HOST:NAME` through a real sshd on 127.0.0.1
(tests/integration/sshd.py) reaches the session server where the publisher runs, and prints the same
exact values as on that machine; the plot's points cross the link as they do locally."""

from __future__ import annotations

import csv
import io
import json
import sys
from pathlib import Path

from ..conftest import run_cli
from .nodes.signal_node import expected
from .sshd import Machine, Machines, machines_fixture  # noqa: F401

SIGNAL_NODE = Path(__file__).resolve().parent / "nodes" / "signal_node.py"
LAUNCH = f"""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='wave', cmd=[
        {sys.executable!r}, {str(SIGNAL_NODE)!r}, 'ssh_wave', '--topic', '/ssh/wave',
        '--rate', '50'])])
"""


def there(machine: Machine) -> dict[str, str]:
    """The environment of a user logged in on `machine`."""
    return {"XDG_RUNTIME_DIR": str(machine.runtime),
            "ROS_LOG_DIR": str(machine.folder / "roslog")}


def test_plot_csv_through_the_ssh_link_prints_what_was_published(machines: Machines, write):
    robot = machines["robot1"]
    path = write(LAUNCH)
    done = run_cli(str(path), "--detach", "--name", "far", env=there(robot))
    assert done.returncode == 0, done.stderr
    try:
        assert run_cli("wait", "far", "wave-1", "running", "--timeout", "60",
                       env=there(robot)).returncode == 0
        # not a session of this machine's: only the link reaches it
        assert "far" not in run_cli("ls").stdout
        plotted = run_cli("plot", "robot1:far", "/ssh/wave", "x", "z", "--csv",
                          "--duration", "4")
        assert plotted.returncode == 0, plotted.stderr
        rows = list(csv.DictReader(io.StringIO(plotted.stdout)))
        assert len(rows) > 20
        samples = [int(float(row["z"])) for row in rows]
        assert samples == list(range(samples[0], samples[0] + len(samples)))
        assert all(float(row["x"]) == expected(k, 50.0, 4.0)[0]
                   for row, k in zip(rows, samples, strict=True))
        wrong = run_cli("plot", "robot1:far", "/ssh/wave", "nope", "--csv")
        assert wrong.returncode != 0 and "Traceback" not in wrong.stderr
        assert "/ssh/wave (geometry_msgs/msg/Point) has no numeric field 'nope'; " \
               "its numeric fields: x, y, z" in wrong.stderr.splitlines()[0]
    finally:
        run_cli("stop", "far", env=there(robot))
    assert json.loads(run_cli("ls", "robot1", "--json").stdout) == []
