"""`tuilaunch logs` as `tail` and as the launch's story: `-n N` (with and without `-f`), and
the starts, exits (code or signal), respawns and restarts of each process among its lines,
in the words --headless prints them, so `--level ERROR` shows a crash."""

from __future__ import annotations

import json
import os
import select
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from ..conftest import run_cli, session_folders, wait_for
from .session_steps import start_here, stop_here
from .test_sessions import wait_state

LAUNCH = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess


def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='three', output='screen',
                       cmd=['sh', '-c', 'echo three says hi; sleep 0.5; exit 3']),
        ExecuteProcess(name='segv', output='screen',
                       cmd=['sh', '-c', 'echo segv says hi; sleep 0.5; kill -SEGV $$']),
        ExecuteProcess(name='again', output='screen', respawn=True, respawn_delay=0.2,
                       respawn_max_retries=1, cmd=['sh', '-c', 'echo again; exit 1']),
        ExecuteProcess(name='counter', output='screen',
                       cmd=['sh', '-c', 'i=1; while [ $i -le 50 ]; do echo line $i; '
                            'i=$((i+1)); done; exec sleep 600']),
    ])
"""


def tl(*args: str) -> str:
    done = run_cli(*args)
    assert done.returncode == 0, done.stderr
    return done.stdout


@contextmanager
def life_session(root: Path) -> Iterator[str]:
    """LAUNCH in a session of its own under `root`, once its story is told: three-1 and
    segv-2 failed, again-3 respawned and gave up, counter-4 printed its 50 lines."""
    (root / "life.launch.py").write_text(LAUNCH)
    with session_folders(root / "log"):
        name = start_here(str(root / "life.launch.py"), "--name", "life")
        try:
            for process, state in (("three-1", "failed"), ("segv-2", "failed"),
                                   ("counter-4", "running")):
                wait_state(name, process, state)
            wait_for(lambda: "respawn gives up" in tl("logs", name, "again-3"),
                     what="2 tries")
            wait_for(lambda: "line 50" in tl("logs", name, "counter-4"), what="50 lines")
            yield name
        finally:
            stop_here(name, gone_ok=True)


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    """One session for the tests that only read it (logs, wait): none changes it."""
    with life_session(tmp_path_factory.mktemp("life")) as name:
        yield name


def test_logs_tell_starts_exits_signals_and_respawns(session):
    three = tl("logs", session, "three-1").splitlines()
    assert three[0].startswith("[INFO] [three-1]: process started with pid [")
    assert three[1] == "three says hi"
    assert three[2].startswith("[ERROR] [three-1]: process has died [pid ")
    assert three[2].endswith(", exit code 3].")
    errors = tl("logs", session, "--level", "ERROR").splitlines()
    assert any("[segv-2]: process has died" in line and "killed by SIGSEGV" in line
               for line in errors), errors
    assert any("[three-1]: process has died" in line for line in errors)
    assert "[ERROR] [again-3]: respawn gives up: it failed 2 times " \
        "(respawn_max_retries=1)" in errors
    assert not any("says hi" in line or "started" in line for line in errors)
    again = tl("logs", session, "again-3")
    assert "[WARN] [again-3]: respawning (try 1 in 0.2 s)" in again
    assert again.count("process started with pid") == 2
    # every process's story, merged in time: a life line is not prefixed twice
    everything = tl("logs", session)
    assert "[segv-2] segv says hi" in everything
    assert "[INFO] [counter-4]: process started with pid [" in everything
    assert "[counter-4] [INFO] [counter-4]" not in everything


def test_a_restart_is_a_stop_asked_for_then_a_start_in_logs_and_in_logs_f(tmp_path):
    """The restart of counter-4, as `logs -f -n 2` shows it as it happens (the last 2
    lines, then the stop and the new start) and as `logs` and `status` tell it after."""
    with life_session(tmp_path) as session:
        follower = subprocess.Popen([sys.executable, "-m", "tuilaunch", "logs", session,
                                     "counter-4", "-f", "-n", "2"], stdout=subprocess.PIPE,
                                    stderr=subprocess.PIPE, text=True)
        try:
            assert follower.stdout is not None
            assert [follower.stdout.readline().rstrip("\n") for _ in range(2)] == [
                "line 49", "line 50"]
            tl("restart", session, "counter-4")
            seen = []
            end = time.monotonic() + 60
            while "line 1" not in seen:
                assert time.monotonic() < end, seen
                seen.append(follower.stdout.readline().rstrip("\n"))
            assert seen[0] == \
                "[INFO] [counter-4]: sending signal 'SIGINT' to process[counter-4]"
            assert seen[1].startswith("[INFO] [counter-4]: process stopped [pid ")
            assert seen[2].startswith("[INFO] [counter-4]: process started with pid [")
            assert seen[3] == "line 1"
            follower.send_signal(signal.SIGINT)
            _, errors = follower.communicate(timeout=30)
            assert follower.returncode == 130
            assert errors == "tuilaunch: interrupted\n"
        finally:
            if follower.poll() is None:
                follower.kill()
                follower.wait()
        wait_for(lambda: tl("logs", session, "counter-4").count("process started") == 2,
                 what="the second start")
        story = [line for line in tl("logs", session, "counter-4").splitlines()
                 if not line.startswith("line ")]
        assert story[0].startswith("[INFO] [counter-4]: process started with pid [")
        # launch's words for the signal sent, then the end it caused
        assert story[1] == "[INFO] [counter-4]: sending signal 'SIGINT' to process[counter-4]"
        assert story[2].startswith("[INFO] [counter-4]: process stopped [pid ")
        assert "killed by SIGINT" in story[2]
        assert story[3].startswith("[INFO] [counter-4]: process started with pid [")
        assert "counter-4" not in tl("logs", session, "--level", "WARN")  # no crash
        # status no longer tells the end before the restart as the process's current story
        counter = next(p for p in json.loads(tl("status", session, "--json"))["processes"]
                       if p["id"] == "counter-4")
        assert counter["state"] == "running"
        assert counter["exit_code"] is None and counter["detail"] is None
        three = next(p for p in json.loads(tl("status", session, "--json"))["processes"]
                     if p["id"] == "three-1")
        assert three["exit_code"] == 3 and three["detail"] == "exit code 3"


def test_waiting_for_a_process_that_ended_for_good_says_so_at_once(session):
    done = run_cli("wait", session, "three-1", "running")  # no --timeout: it must not hang
    assert done.returncode == 1
    assert done.stderr.startswith("tuilaunch wait: three-1 failed, not running")
    assert f"tuilaunch restart {session} three-1 starts it again" in done.stderr


def test_ctrl_c_on_wait_says_interrupted(session):
    waiting = subprocess.Popen([sys.executable, "-m", "tuilaunch", "wait", session,
                                "counter-4", "exited"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        # waiting once it holds its connection to the session (a socket among its files)
        wait_for(lambda: waiting.poll() is None and _has_socket(waiting.pid), what="waiting")
        waiting.send_signal(signal.SIGINT)
        out, errors = waiting.communicate(timeout=30)
        assert waiting.returncode == 130 and out == ""
        assert errors == "tuilaunch: interrupted\n"
    finally:
        if waiting.poll() is None:
            waiting.kill()
            waiting.wait()


def _has_socket(pid: int) -> bool:
    folder = Path(f"/proc/{pid}/fd")
    try:
        return any(os.readlink(folder / fd).startswith("socket:") for fd in os.listdir(folder))
    except OSError:
        return False


def test_lines_keeps_the_last_n_as_tail(session):
    assert tl("logs", session, "counter-4", "-n", "3").splitlines() == [
        "line 48", "line 49", "line 50"]
    assert tl("logs", session, "counter-4", "--lines", "0") == ""
    # with a filter: the last N of what passes it
    assert len(tl("logs", session, "--level", "ERROR", "-n", "2").splitlines()) == 2
    bad = run_cli("logs", session, "-n", "-2")
    assert bad.returncode == 2 and "--lines -2 is not a number of lines" in bad.stderr
    assert "Traceback" not in bad.stderr


STUBBORN = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess


def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='stubborn', output='screen', sigterm_timeout='4',
                       cmd=['sh', '-c', 'trap "" INT; echo ready; '
                            'while true; do sleep 0.2 || true; done']),
    ])
"""


def test_stop_says_what_it_waits_for_while_a_process_ignores_sigint(tmp_path):
    (tmp_path / "stubborn.launch.py").write_text(STUBBORN)
    with session_folders(tmp_path / "log"):
        name = start_here(str(tmp_path / "stubborn.launch.py"), "--name", "stub")
        wait_for(lambda: "ready" in tl("logs", name, "stubborn-1"), what="ready")
        stopped = run_cli("stop", name)
        assert stopped.returncode == 0, stopped.stderr
        assert stopped.stdout == f"session {name} stopped\n"
        assert "tuilaunch stop: waiting for stubborn-1 (" in stopped.stderr
        assert "tuilaunch stop: stubborn-1: process[stubborn-1] failed to terminate '4' " \
            "seconds after receiving 'SIGINT', escalating to 'SIGTERM'" in stopped.stderr
        assert "Traceback" not in stopped.stderr


SAYING = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess, LogInfo, RegisterEventHandler
from launch.event_handlers import OnProcessExit


def generate_launch_description():
    gate = ExecuteProcess(name='gate', output='screen', cmd=[
        'sh', '-c', 'echo waiting; while [ ! -e {flag} ]; do sleep 0.05; done; echo through'])
    return LaunchDescription([
        LogInfo(msg='bringing the gate up'),
        gate,
        RegisterEventHandler(OnProcessExit(target_action=gate,
                                           on_exit=[LogInfo(msg='the gate is through')])),
    ])
"""


def lines_of(proc: subprocess.Popen[bytes], count: int, limit: float = 60.0) -> list[str]:
    """The next `count` lines `proc` prints; a failure, not a hang, when they do not come.
    Read unbuffered, so that select() sees every byte not read yet."""
    assert proc.stdout is not None
    fd = proc.stdout.fileno()
    end = time.monotonic() + limit
    data = b""
    while data.count(b"\n") < count:
        assert select.select([fd], [], [], max(0.0, end - time.monotonic()))[0], \
            f"only {data!r} within {limit:g} s"
        chunk = os.read(fd, 1 << 16)
        assert chunk, f"the output ended after {data!r}"
        data += chunk
    assert data.count(b"\n") == count, data  # nothing read past them is lost unseen
    return data.decode().splitlines(keepends=True)


def test_logs_of_a_whole_session_have_the_launch_files_own_lines_as_headless(tmp_path):
    """`ros2 launch` prints a LogInfo's line among the processes' (`[INFO] [launch.user]:
    ...`); `logs NAME` of a session is that output read back, so it has them, in time
    order, and follows them with -f; `logs NAME PROCESS` is that process's alone."""
    flag = tmp_path / "open"
    (tmp_path / "saying.launch.py").write_text(SAYING.replace("{flag}", str(flag)))
    with session_folders(tmp_path / "log"):
        name = start_here(str(tmp_path / "saying.launch.py"))
        try:
            wait_for(lambda: "waiting" in tl("logs", name, "gate-1"), what="the gate")
            follow = subprocess.Popen([sys.executable, "-m", "tuilaunch", "logs", name, "-f"],
                                      stdout=subprocess.PIPE, bufsize=0)
            try:
                first = lines_of(follow, 3)
                assert first[0] == "[INFO] [launch.user]: bringing the gate up\n"
                assert first[1].startswith("[INFO] [gate-1]: process started with pid [")
                assert first[2] == "[gate-1] waiting\n"
                flag.touch()
                later = lines_of(follow, 3)
                assert later[0] == "[gate-1] through\n"
                assert later[1].startswith("[INFO] [gate-1]: process has finished cleanly")
                assert later[2] == "[INFO] [launch.user]: the gate is through\n"
            finally:
                follow.kill()
                follow.wait()
            lines = tl("logs", name).splitlines()
            assert [lines[0], lines[-1]] == ["[INFO] [launch.user]: bringing the gate up",
                                             "[INFO] [launch.user]: the gate is through"]
            assert "launch.user" not in tl("logs", name, "gate-1")
            assert tl("logs", name, "--level", "WARN") == ""
        finally:
            stop_here(name, gone_ok=True)


TWICE = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess, OpaqueFunction, RegisterEventHandler
from launch.event_handlers import OnProcessStart


def say(context):
    print('first thing said')
    print('second thing said')
    return []


def generate_launch_description():
    sleeper = ExecuteProcess(name='sleeper', cmd=['sleep', '600'])
    return LaunchDescription([sleeper, RegisterEventHandler(OnProcessStart(
        target_action=sleeper, on_start=[OpaqueFunction(function=say)]))])
"""


def test_two_launch_lines_said_within_a_millisecond_are_both_in_logs(tmp_path):
    """What launch-time code prints while the launch runs is launch lines; two printed one
    after the other share their millisecond, and neither is taken for a repeat."""
    (tmp_path / "twice.launch.py").write_text(TWICE)
    with session_folders(tmp_path / "log"):
        name = start_here(str(tmp_path / "twice.launch.py"))
        try:
            wait_for(lambda: "second thing said" in tl("logs", name), what="both lines")
            said = [line for line in tl("logs", name).splitlines() if "thing said" in line]
            assert said == ["[INFO] [launch.user]: first thing said",
                            "[INFO] [launch.user]: second thing said"]
        finally:
            stop_here(name, gone_ok=True)
