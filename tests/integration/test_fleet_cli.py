"""The command line over a fleet: `ls HOST HOST ...`, and `status`, `stop`, `logs -f` of
several sessions on several machines, through real sshd "machines" on 127.0.0.1
(tests/integration/sshd.py), each robot's launch on a ROS domain of its own.

One robot that cannot be reached, or one session that is not there, is one line naming it;
the others are listed, stopped, followed, and the exit status says something failed.
"""

from __future__ import annotations

import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from ..conftest import run_cli, wait_for
from .sshd import Machine, Machines, alive, machines_fixture, proxies_on  # noqa: F401
from .test_completion import Shell
from .test_remote_sessions import LAUNCH, there
from .test_sessions import runtime  # noqa: F401


def domain(offset: int) -> str:
    """A ROS domain of this test's own, one per robot."""
    return str((int(os.environ.get("ROS_DOMAIN_ID", "0")) + 100 * offset) % 200)


def start(machine: Machine, write, name: str, offset: int) -> int:
    """A session started on `machine` (as a user logged in there would), on a ROS domain of
    its own; its server's pid."""
    return started(machine, write(LAUNCH), name, offset)


def start_all(write, *sessions: tuple[Machine, str, int]) -> list[int]:
    """Sessions started as `start` starts one (machine, name, domain offset), all at once:
    their servers' pids, in order."""
    path = write(LAUNCH)
    with ThreadPoolExecutor() as pool:
        return list(pool.map(lambda session: started(session[0], path, *session[1:]),
                             sessions))


def started(machine: Machine, path: Path, name: str, offset: int) -> int:
    env = {**there(machine), "ROS_DOMAIN_ID": domain(offset)}
    done = run_cli(str(path), "--detach", "--name", name, env=env)
    assert done.returncode == 0, done.stderr
    assert run_cli("wait", name, "ticker-1", "running", "--timeout", "30",
                   env=env).returncode == 0
    return machine.server_pid(name)


def with_gone_host(machines: Machines) -> None:
    """`gone`: a host of the ssh config where nobody listens."""
    machines.ssh_config.write_text(machines.ssh_config.read_text() +
                                   machines.host_entry("gone", 1))


@pytest.mark.usefixtures("runtime")  # this computer's sessions: the test's own
def test_ls_lists_every_host_in_one_table_and_says_the_one_it_cannot_reach(machines, write):
    start_all(write, (machines["robot1"], "base", 0), (machines["robot2"], "arm", 1))
    with_gone_host(machines)

    listed = run_cli("ls", "robot1", "gone", "robot2")
    assert listed.returncode == 2  # something failed ...
    lines = listed.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("tuilaunch ls: error: cannot reach gone")
    table = listed.stdout.splitlines()  # ... and the others are listed all the same
    assert table[0].split()[:3] == ["HOST", "NAME", "PID"]
    rows = [[*line.split()[:2], line.split()[5]] for line in table[1:]]  # STARTED: 2 words
    assert rows == [["robot1", "base", "2/2"], ["robot2", "arm", "2/2"]]

    both = run_cli("ls", "robot2", "robot1", "--json")
    assert both.returncode == 0, both.stderr
    assert [(s["host"], s["name"], s["counts"]["running"]) for s in json.loads(both.stdout)] \
        == [("robot2", "arm", 2), ("robot1", "base", 2)]
    # `local` is this computer, whose sessions are neither robot's
    assert run_cli(str(write(LAUNCH)), "--detach", "--name", "home").returncode == 0
    here = run_cli("ls", "local", "robot1", "--json")
    assert here.returncode == 0, here.stderr
    assert [(s["host"], s["name"]) for s in json.loads(here.stdout)] == [
        ("local", "home"), ("robot1", "base")]
    assert run_cli("stop", "local:home").returncode == 0
    for done in (listed, both, here):
        assert "Traceback" not in done.stderr


def test_status_and_stop_of_several_sessions_in_one_command(machines, write):
    first, second, third = start_all(write, (machines["robot1"], "base", 0),
                                     (machines["robot2"], "arm", 1),
                                     (machines["robot1"], "lidar", 0))

    status = run_cli("status", "robot1:base", "robot2:arm", "--json")
    assert status.returncode == 0, status.stderr
    answers = json.loads(status.stdout)
    assert [(a["session"], a["pid"]) for a in answers] == [("robot1:base", first),
                                                           ("robot2:arm", second)]
    assert all(p["state"] == "running" for a in answers for p in a["processes"])
    text = run_cli("status", "robot2:arm", "robot2:nothere", "robot1:base")
    assert text.returncode == 2
    assert "session robot2:arm  pid" in text.stdout and "session robot1:base  pid" in \
        text.stdout
    assert text.stderr.splitlines() == [
        "tuilaunch status: error: robot2: no running session named nothere; running: arm"]

    # one that is not there: said, and the other is stopped all the same
    stopped = run_cli("stop", "robot1:base", "robot2:nothere", "robot2:arm")
    assert stopped.returncode == 2
    assert sorted(stopped.stdout.splitlines()) == ["session robot1:base stopped",
                                                   "session robot2:arm stopped"]
    assert "robot2: no running session named nothere" in stopped.stderr
    wait_for(lambda: not alive(first) and not alive(second))
    assert alive(third)  # robot1's other session was not asked to stop

    # HOST: is every session there
    everything = run_cli("stop", "robot1:")
    assert everything.returncode == 0, everything.stderr
    assert everything.stdout.splitlines() == ["session robot1:lidar stopped"]
    wait_for(lambda: not alive(third))
    listed = run_cli("ls", "robot1", "robot2", "--json")
    assert json.loads(listed.stdout) == []
    for done in (status, text, stopped, everything):
        assert "Traceback" not in done.stderr


def test_logs_follow_of_two_sessions_prefixes_each_line_and_says_each_end(machines, write):
    start_all(write, (machines["robot1"], "base", 0), (machines["robot2"], "arm", 1))
    follow = subprocess.Popen(
        [sys.executable, "-m", "tuilaunch", "logs", "robot1:base", "robot2:arm", "ticker-1",
         "-f"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        start_new_session=True)
    lines: queue.Queue[tuple[str, str]] = queue.Queue()

    def read(stream, name: str) -> None:
        for line in stream:
            lines.put((name, line.rstrip("\n")))

    readers = [threading.Thread(target=read, args=(s, n), daemon=True)
               for s, n in ((follow.stdout, "out"), (follow.stderr, "err"))]
    for reader in readers:
        reader.start()
    seen: dict[str, list[str]] = {"out": [], "err": []}

    def until(check, what: str) -> None:
        def got() -> bool:
            try:
                while True:
                    name, line = lines.get_nowait()
                    seen[name].append(line)
            except queue.Empty:
                pass
            return bool(check())
        wait_for(got, what=what)

    def ticks(session: str) -> list[str]:
        return [line[len(session) + 1:] for line in seen["out"]
                if line.startswith(session + " tick ")]

    try:
        until(lambda: len(ticks("robot1:base")) >= 5 and len(ticks("robot2:arm")) >= 5,
              "ticks of both sessions")
        for session in ("robot1:base", "robot2:arm"):  # each session's lines, in order
            shown = ticks(session)
            assert shown == [f"tick {i}" for i in range(1, len(shown) + 1)]
        assert all(line.startswith(("robot1:base ", "robot2:arm ")) for line in seen["out"])

        # one session stopped: said, and the other followed on
        assert run_cli("stop", "robot2:arm").returncode == 0
        until(lambda: "tuilaunch logs: robot2:arm: the session ended" in seen["err"],
              "the end of robot2:arm said")
        now = len(ticks("robot1:base"))
        until(lambda: len(ticks("robot1:base")) > now + 3, "robot1:base followed on")
        assert follow.poll() is None

        # the other's link cut: said, and with nothing left to follow, a failed exit
        for pid in proxies_on(machines["robot1"]):
            os.kill(pid, signal.SIGKILL)
        until(lambda: any(line.startswith("tuilaunch logs: robot1:base: link to robot1 lost")
                          for line in seen["err"]),
              "the lost link said")
        assert follow.wait(timeout=60) == 2
    finally:
        if follow.poll() is None:
            os.killpg(follow.pid, signal.SIGTERM)
        follow.wait()
    assert not any("Traceback" in line for line in seen["err"])
    assert run_cli("stop", "robot1:base").returncode == 0


@pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")
def test_tab_offers_the_hosts_of_the_ssh_config_and_their_sessions(machines, write, tmp_path):
    start(machines["robot1"], write, "base", 0)
    home = tmp_path / "home"
    home.mkdir()
    # the hosts of the ssh config tuilaunch's ssh reads (-F here), without its patterns
    machines.ssh_config.write_text(machines.ssh_config.read_text() + "Host *.lab !x\n")
    shell = Shell("bash", home, tmp_path)
    try:
        shell.tab("tuilaunch stop rob", ["robot1:", "robot2:"])
        shell.completes("tuilaunch stop robot1:", "tuilaunch stop robot1:base ")
        shell.completes("tuilaunch logs robot1:base robot2", "tuilaunch logs robot1:base "
                        "robot2:")
        screen = shell.tab("tuilaunch ls ", ["local", "robot1", "robot2"])
        assert ".lab" not in screen
    finally:
        shell.close()
    assert run_cli("stop", "robot1:base").returncode == 0
