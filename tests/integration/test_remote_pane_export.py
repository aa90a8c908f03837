"""A TUI attached over ssh (`tuilaunch attach robot1:far` in tmux, robot1 a real sshd:
tests/integration/sshd.py) to a node printing faster than a link sends a display: the link
dropped and made again, `w` at once saves every line the pane stands for (the runs the link
did not send read back through the session, not their marker lines), as the log file over
there has them; a reconnection attempt that hangs is said as under way, with its number
and seconds, in 80 columns."""

from __future__ import annotations

import os
import re
import shutil
import signal
from pathlib import Path

import pytest

from ..conftest import wait_for
from .session_steps import start_here, stop_here
from .sshd import Machines, machines_fixture, proxies_on  # noqa: F401
from .test_placed_terminal import Tmux

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")

LAUNCH = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(name='ticker', cmd=[
        'sh', '-c', 'i=0; while true; do i=$((i+1)); echo tick $i; sleep 0.01; done']))
    return sl.launch_description()
"""


def ticks(lines: list[str]) -> list[int]:
    return [int(line.split()[-1]) for line in lines if re.fullmatch(r"tick \d+", line)]


def test_w_right_after_a_reconnect_saves_every_line_the_pane_stands_for(
        machines: Machines, write, tmp_path: Path, monkeypatch) -> None:
    robot = machines["robot1"]
    there = {"XDG_RUNTIME_DIR": str(robot.runtime), "ROS_LOG_DIR": str(robot.folder / "log")}
    with pytest.MonkeyPatch.context() as patch:  # the setting, from this process
        for key, value in there.items():
            patch.setenv(key, value)
        start_here(write(LAUNCH), "--name", "far")
    monkeypatch.setenv("ROS_LOG_DIR", str(tmp_path / "here"))  # where w writes, here
    tui = Tmux(tmp_path, "attach", "robot1:far")
    try:
        tui.select("ticker-1")
        # the flood: the link sends a screenful a second, the rest stands as marker lines
        tui.wait_for("not drawn (in log)")
        for pid in proxies_on(robot):
            os.kill(pid, signal.SIGKILL)  # the link dies; ssh ends with it
        tui.wait_for("link to robot1 lost")
        wait_for(lambda: "link to robot1 lost" not in tui.screen(), 90, "the link back")
        assert "not drawn (in log)" in tui.screen()  # the pane holds marker lines
        tui.keys("w")
        tui.wait_for("pane saved to", 60)
        saved = list((tmp_path / "here" / "tuilaunch-robot1-far").glob("ticker-1-pane-*.txt"))
        assert len(saved) == 1, saved
        lines = saved[0].read_text().splitlines()
        assert not [line for line in lines if "not drawn" in line], "a marker was saved"
        got = ticks(lines)
        # every line from the first the pane holds to the last, none twice, as logged
        assert got == list(range(got[0], got[-1] + 1)), "a line is missing or twice"
        logged = ticks([line.split(" ", 2)[-1] for line in  # "TIME STREAM TEXT"
                        next((robot.folder / "log").rglob("ticker-1.log")).read_text()
                        .splitlines()])
        assert got == logged[got[0] - 1:got[-1]]

        # robot1 hangs (its sshd stopped): the next attempt is said as under way, with
        # its number and seconds, not the last attempt's reason alone
        os.kill(robot.proc.pid, signal.SIGSTOP)
        try:
            for pid in proxies_on(robot):
                os.kill(pid, signal.SIGKILL)
            top = tui.wait_for("retrying (attempt 1, ", 60).splitlines()[0]
            assert top.startswith(" link to robot1 lost · retrying (attempt 1, "), top
            assert " · last: " in top and len(top.rstrip()) <= 80, top
            wait_for(lambda: re.search(r"attempt 1, [3-9] s",
                                       tui.screen().splitlines()[0]) is not None,
                     30, "its seconds counted")
        finally:
            os.kill(robot.proc.pid, signal.SIGCONT)
        wait_for(lambda: "link to robot1 lost" not in tui.screen(), 120, "the link back")
    finally:
        tui.close()
        with pytest.MonkeyPatch.context() as patch:
            for key, value in there.items():
                patch.setenv(key, value)
            stop_here("far", gone_ok=True)
