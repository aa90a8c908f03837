"""A plot over ssh: `tuilaunch plot HOST:NAME` through a real sshd on 127.0.0.1
(tests/integration/sshd.py) reaches the session server where the publisher runs, and prints the same
exact values as on that machine; the plot's points cross the link as they do locally."""

from __future__ import annotations

import csv
import fcntl
import io
import json
import os
import pty
import re
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
from pathlib import Path

from ..conftest import run_cli, wait_for
from .nodes.signal_node import expected
from .session_steps import start_here, stop_here
from .sshd import Machine, Machines, machines_fixture, proxies_on  # noqa: F401
from .test_remote_sessions import logged_in
from .test_sessions import wait_state

SIGNAL_NODE = Path(__file__).resolve().parent / "nodes" / "signal_node.py"
LAUNCH = f"""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='wave', cmd=[
        {sys.executable!r}, {str(SIGNAL_NODE)!r}, 'ssh_wave', '--topic', '/ssh/wave',
        '--rate', '50'])])
"""


def test_plot_csv_through_the_ssh_link_prints_what_was_published(machines: Machines, write):
    robot = machines["robot1"]
    path = write(LAUNCH)
    with logged_in(robot):  # the setting, from this process: the plot is the subject
        start_here(path, "--name", "far")
    try:
        with logged_in(robot):
            wait_state("far", "wave-1", "running")
        # not a session of this machine's: only the link reaches it
        assert "far" not in run_cli("ls").stdout
        plotted = run_cli("plot", "robot1:far", "/ssh/wave", "x", "z", "--csv",
                          "--duration", "4")
        assert plotted.returncode == 0, plotted.stderr
        rows = list(csv.DictReader(io.StringIO(plotted.stdout)))
        assert len(rows) > 20
        samples = [int(float(row["/ssh/wave/z"])) for row in rows]
        assert samples == list(range(samples[0], samples[0] + len(samples)))
        assert all(float(row["/ssh/wave/x"]) == expected(k, 50.0, 4.0)[0]
                   for row, k in zip(rows, samples, strict=True))
        wrong = run_cli("plot", "robot1:far", "/ssh/wave", "nope", "--csv")
        assert wrong.returncode != 0 and "Traceback" not in wrong.stderr
        assert "/ssh/wave (geometry_msgs/msg/Point) has no numeric field 'nope'; " \
               "its numeric fields: x, y, z" in wrong.stderr.splitlines()[0]
    finally:
        with logged_in(robot):
            stop_here("far", gone_ok=True)
    assert json.loads(run_cli("ls", "robot1", "--json").stdout) == []


class PtyPlot:
    """`tuilaunch plot ...` full screen on a pty of 80x24, all it writes kept as text."""

    def __init__(self, *args: str) -> None:
        master, slave = pty.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
        self.proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", "plot", *args],
                                     stdin=slave, stdout=slave, stderr=slave,
                                     env={**os.environ, "TERM": "xterm-256color"},
                                     start_new_session=True)
        os.close(slave)
        self.master = master
        self.text = ""
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        while True:
            try:
                data = os.read(self.master, 65536)
            except OSError:
                return
            if not data:
                return
            self.text += data.decode(errors="replace")

    def ended(self) -> tuple[int, str]:
        """Its exit status, and the last line it wrote (once the screen was put back)."""
        try:
            self.proc.wait(timeout=60)
        finally:
            if self.proc.poll() is None:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        time.sleep(0.2)  # the last bytes read
        os.close(self.master)
        said = re.findall(r"tuilaunch plot: [^\r\n\x1b]*", self.text)
        return self.proc.returncode, said[-1] if said else self.text[-300:]


def test_the_full_screen_plot_says_a_lost_link_and_an_ended_session_apart(
        machines: Machines, write):
    """As hz and echo: the link's end is `link to HOST lost: REASON`, status 1 (the session
    runs on); the session's end is `session ... ended`, status 2."""
    robot = machines["robot1"]
    with logged_in(robot):  # the setting, from this process: the plot is the subject
        start_here(write(LAUNCH), "--name", "far")
    try:
        with logged_in(robot):
            wait_state("far", "wave-1", "running")
        plot = PtyPlot("robot1:far", "/ssh/wave", "x")
        wait_for(lambda: "last" in plot.text and len(proxies_on(robot)) == 1, 60,
                 "the plot drawn")
        for pid in proxies_on(robot):  # the far end of the link dies
            os.kill(pid, signal.SIGKILL)
        code, said = plot.ended()
        assert code == 1 and said.startswith("tuilaunch plot: link to robot1 lost: "), \
            (code, said)
        assert len(said.split("lost: ", 1)[1].strip()) > 0
        with logged_in(robot):
            wait_state("far", "wave-1", "running", timeout=10)  # it ran on

        plot = PtyPlot("robot1:far", "/ssh/wave", "x")
        wait_for(lambda: "last" in plot.text, 60, "the plot drawn")
        assert run_cli("stop", "robot1:far").returncode == 0
        code, said = plot.ended()
        assert code == 2 and said == "tuilaunch plot: error: session robot1:far ended", \
            (code, said)
    finally:
        with logged_in(robot):
            stop_here("far", gone_ok=True)
