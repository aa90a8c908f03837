"""`tuilaunch stop NAME PROCESS [...]` and `tuilaunch start NAME PROCESS [...]`: some
processes of one session stopped or started from the command line, the rest of the launch
and the session left running; here and over ssh (`robot1:NAME`, a real sshd on 127.0.0.1).

One session serves the module: it runs on "robot1" (tests/integration/sshd.py), so the same
session is reached by its name with robot1's runtime folder (as a user logged in there) and
as `robot1:pc` over ssh. Each test leaves it as it found it.
"""

from __future__ import annotations

import json
import textwrap
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import pytest

from ..conftest import run_cli
from .sshd import Machines
from .test_remote_sessions import there

LAUNCH = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('extra', default_value='false'),
        ExecuteProcess(name='ticker', cmd=[
            'sh', '-c', 'i=0; while true; do i=$((i+1)); echo tick $i; sleep 0.2; done']),
        ExecuteProcess(name='quiet', cmd=['sleep', '600']),
        Node(package='tuilaunch_demos', executable='talker', name='talker', namespace='pc'),
        ExecuteProcess(name='extra', cmd=['sleep', '600'],
                       condition=IfCondition(LaunchConfiguration('extra'))),
    ])
"""
RUNNING = ("ticker-1", "quiet-2", "talker-3")


@dataclass
class Robot:
    env: dict[str, str]

    def cli(self, *args: str) -> Any:
        return run_cli(*args, env=self.env)

    def states(self) -> dict[str, tuple[str, int | None]]:
        done = self.cli("status", "pc", "--json")
        assert done.returncode == 0, done.stderr
        return {p["id"]: (p["state"], p["pid"]) for p in json.loads(done.stdout)["processes"]}

    def running(self, *processes: str) -> None:
        """Starts them again (a test's end): they run, whatever the test did."""
        done = self.cli("start", "pc", *processes)
        assert done.returncode == 0, done.stderr
        states = self.states()
        assert all(states[p][0] == "running" for p in processes), states


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Robot]:
    root = tmp_path_factory.mktemp("proccmd")
    fleet = Machines(root / "ssh", aliases=("robot1",))
    try:
        path = root / "procs.launch.py"
        path.write_text(textwrap.dedent(LAUNCH))
        robot = Robot({**fleet.env(), **there(fleet["robot1"])})
        started = robot.cli(str(path), "--detach", "--name", "pc")
        assert started.returncode == 0, started.stderr
        for process in RUNNING:
            waited = robot.cli("wait", "pc", process, "running", "--timeout", "60")
            assert waited.returncode == 0, waited.stderr
        yield robot
        robot.cli("stop", "pc")
    finally:
        fleet.stop()  # whatever is left under robot1 ends with it


def test_stop_stops_the_processes_named_and_nothing_else(robot):
    before = robot.states()
    # an id and a full node name; the stop returns once both are stopped
    done = robot.cli("stop", "pc", "ticker-1", "/pc/talker")
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["ticker-1 stopped", "talker-3 stopped"]
    after = robot.states()
    assert after["ticker-1"][0] == after["talker-3"][0] == "exited"
    assert after["quiet-2"] == before["quiet-2"]  # the same process, untouched
    assert robot.cli("status", "pc").returncode == 0  # the session runs on

    again = robot.cli("stop", "pc", "ticker-1")  # a second stop is no error
    assert (again.returncode, again.stdout) == (0, "ticker-1 was not running (exited)\n")

    started = robot.cli("start", "pc", "ticker-1", "talker", "quiet-2")  # a unique node name
    assert started.returncode == 0, started.stderr
    assert started.stdout.splitlines() == ["ticker-1 started", "talker-3 started",
                                           "quiet-2 was running already"]
    states = robot.states()
    assert all(states[p][0] == "running" for p in RUNNING), states
    assert states["quiet-2"] == before["quiet-2"]


def test_a_word_that_is_neither_a_process_nor_a_session_stops_nothing(robot):
    before = robot.states()
    typo = robot.cli("stop", "pc", "quiet-2", "tickr")
    assert typo.returncode == 2
    assert typo.stderr == ("tuilaunch stop: error: 'tickr' is neither a process of session "
                           "pc nor a session (did you mean 'ticker-1'?): nothing was "
                           "stopped\n")
    nothing = robot.cli("stop", "pc", "zzz")
    assert nothing.returncode == 2
    assert nothing.stderr.splitlines() == [
        "tuilaunch stop: error: 'zzz' is neither a process of session pc nor a session "
        "(processes: ticker-1, quiet-2, talker-3, extra-4): nothing was stopped"]
    # a session named among processes, and a first word that names no session
    mixed = robot.cli("stop", "pc", "pc", "quiet-2")
    assert mixed.returncode == 2
    assert mixed.stderr.splitlines() == [
        "tuilaunch stop: error: pc is a session, not a process of session pc (stop takes "
        "several sessions, or one session and its processes): nothing was stopped"]
    nosession = robot.cli("stop", "pq", "pc")
    assert nosession.returncode == 2
    assert nosession.stderr.splitlines()[0] == \
        "tuilaunch stop: error: no running session named pq"
    start = robot.cli("start", "pc", "quiet2")
    assert start.returncode == 2
    assert start.stderr.splitlines() == [
        "tuilaunch start: error: 'quiet2' is neither a process of session pc nor a session "
        "(did you mean 'quiet-2'?): nothing was started"]
    assert robot.states() == before  # nothing stopped, not even the words before the typo


def test_start_refuses_a_process_its_condition_skipped(robot):
    done = robot.cli("start", "pc", "ticker-1", "extra-4")
    assert done.returncode == 2
    assert done.stderr.splitlines() == [
        "tuilaunch start: error: extra-4 of session pc is skipped by a condition: the launch "
        "does not run it (a relaunch with values that enable it does); nothing was started"]
    assert robot.states()["extra-4"] == ("skipped", None)


def test_json_says_each_process_and_its_state(robot):
    done = robot.cli("stop", "pc", "quiet-2", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == [{"process": "quiet-2", "state": "exited",
                                        "was": "running"}]
    done = robot.cli("start", "pc", "quiet-2", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == [{"process": "quiet-2", "state": "running",
                                        "was": "exited"}]


def test_host_name_process_works_over_ssh(robot):
    before = robot.states()
    done = robot.cli("stop", "robot1:pc", "ticker-1")
    assert done.returncode == 0, done.stderr
    assert done.stdout == "ticker-1 stopped\n"
    after = robot.states()
    assert after["ticker-1"][0] == "exited"
    assert after["talker-3"] == before["talker-3"]
    typo = robot.cli("stop", "robot1:pc", "talkr")
    assert typo.returncode == 2
    assert typo.stderr.splitlines() == [
        "tuilaunch stop: error: 'talkr' is neither a process of session robot1:pc nor a "
        "session (did you mean 'talker-3'?): nothing was stopped"]
    started = robot.cli("start", "robot1:pc", "ticker-1")
    assert (started.returncode, started.stdout) == (0, "ticker-1 started\n"), started.stderr
    assert robot.states()["ticker-1"][0] == "running"


def test_errors_name_the_session_as_typed_over_ssh(robot):
    """What the session refuses is said with the address typed, not the bare name: with
    two robots each running `pc`, `session pc` would not say which."""
    level = robot.cli("log-level", "robot1:pc", "nobody", "info")
    assert level.returncode == 2
    assert level.stderr.startswith("tuilaunch log-level: error: session robot1:pc: no node or "
                                   "process 'nobody' in this launch"), level.stderr
    plot = robot.cli("plot", "robot1:pc", "/pc/chatter", "nofield", "--csv")
    assert plot.returncode == 2
    assert plot.stderr.startswith("tuilaunch plot: error: session robot1:pc: /pc/chatter "
                                  "(std_msgs/msg/String) has no numeric field 'nofield'"), \
        plot.stderr
