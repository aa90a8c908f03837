"""Talking to a node through its session: typing into its terminal (one client at a time),
crashes reported as failures everywhere, a restart under gdb and back, launch prefixes as
ros2 launch applies them, and the exact command line a node was started with.

Real processes: the session server is started by the command line, the test programs are
the line reader, the raw-key reader (as teleop_twist_keyboard reads) and a segfaulting
program of tests/integration/programs.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tuilaunch.client.link import Link
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.engine.run.vocabulary.requests import Input, Stop, Subscribe, TakeKeys

from ..conftest import run_cli, run_headless, session_folders, wait_for
from .gdb_support import requires_gdb
from .session_steps import start_here, stop_here
from .terminal_harness import PROGRAMS
from .test_sessions import (  # noqa: F401  (runtime: a fixture)
    Terminal,
    cli_status,
    runtime,
    status,
    tl,
    wait_state,
)

pytestmark = pytest.mark.usefixtures("runtime")  # a private session folder per test

LAUNCH = f"""
import sys
from launch import LaunchDescription
from launch.actions import ExecuteProcess
PROGRAMS = {str(PROGRAMS)!r}
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='lines', cmd=[sys.executable, PROGRAMS + '/line_reader.py'],
                       output='screen', emulate_tty=True),
        ExecuteProcess(name='keys', cmd=[sys.executable, PROGRAMS + '/raw_key_reader.py'],
                       output='screen', emulate_tty=True),
        ExecuteProcess(name='segv', cmd=[sys.executable, PROGRAMS + '/segv.py'],
                       output='screen', additional_env={{'CRASH_NOTE': 'a b'}}),
    ])
"""


def logs(name: str, process: str) -> str:
    return tl("logs", name, process).stdout


def process(name: str, process_id: str) -> dict:
    return next(p for p in status(name)["processes"] if p["id"] == process_id)


def start(write) -> str:
    return start_file(write(LAUNCH))


def start_file(path: Path) -> str:
    """A session of LAUNCH at `path`, once both readers are ready."""
    name = start_here(str(path))
    wait_state(name, "lines-1", "running")
    wait_state(name, "keys-2", "running")
    wait_for(lambda: "ready" in logs(name, "lines-1") and "ready" in logs(name, "keys-2"),
             what="both readers ready")
    return name


@pytest.fixture(scope="module")
def shared_session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path]]:
    """One session of LAUNCH for the tests that leave it as they found it (a refused
    restart, a status read, a line typed and the keys given back): its name and folder."""
    root = tmp_path_factory.mktemp("interact")
    path = root / "test_launch.py"
    path.write_text(LAUNCH)
    with session_folders(root / "log") as folder:
        name = start_file(path)
        try:
            yield name, folder
        finally:
            stop_here(name, gone_ok=True)


@pytest.fixture
def shared(shared_session: tuple[str, Path], runtime, monkeypatch) -> str:  # noqa: F811
    """The shared session's name, its folder this test's (in place of `runtime`'s)."""
    name, folder = shared_session
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(folder))
    return name


def test_a_client_types_lines_and_keys_and_ctrl_c_is_sigint_or_a_key(write):
    name = start(write)
    typist, other = Link(name), Link(name)
    try:
        with pytest.raises(SessionError, match="nobody holds the keyboard"):
            typist.request(Input(process="lines-1", data="x\r"))
        other.request(Subscribe())
        typist.request(TakeKeys(process="lines-1", on=True))
        # only one client types at a time; the others are told who does
        with pytest.raises(SessionError, match=r"another client .* is typing into lines-1"):
            other.request(TakeKeys(process="lines-1", on=True))
        with pytest.raises(SessionError, match="refused"):
            other.request(Input(process="lines-1", data="x\r"))
        assert status(name)["typing"]["process"] == "lines-1"
        typist.request(Input(process="lines-1", data="hello robot\r"))
        wait_for(lambda: "got: hello robot" in logs(name, "lines-1"), what="the typed line")
        # the raw reader: keys one by one, ctrl+c is a key for it
        typist.request(TakeKeys(process="keys-2", on=True))
        typist.request(Input(process="keys-2", data="w\u0003"))
        wait_for(lambda: "key: '\\x03'" in logs(name, "keys-2"), what="ctrl+c as a key")
        assert "key: 'w'" in logs(name, "keys-2")
        assert process(name, "keys-2")["state"] == "running"
        # the line reader: ctrl+c is SIGINT, as in a terminal
        typist.request(TakeKeys(process="lines-1", on=True))
        typist.request(Input(process="lines-1", data="\u0003"))
        wait_state(name, "lines-1", "exited")
        assert "interrupted by SIGINT" in logs(name, "lines-1")
        # typing into a node that is not running: one line, nothing else changes
        with pytest.raises(SessionError, match="lines-1 is not running"):
            typist.request(Input(process="lines-1", data="x\r"))
        events = [event for message in other.pending for event in message["events"]
                  if event["kind"] == "typing"]
        assert events and events[0]["process"] == "lines-1"
        assert events[0]["data"]["client"] is not None
    finally:
        typist.close()
    # a client that is gone gives the keyboard back
    wait_for(lambda: status(name)["typing"] is None, what="the keyboard given back")
    other.request(TakeKeys(process="keys-2", on=True))
    other.request(Input(process="keys-2", data="q"))
    wait_state(name, "keys-2", "exited")
    other.close()
    stop_here(name)


PIPED = f"""
import sys
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='lines', output='screen',
                       cmd=[sys.executable, {str(PROGRAMS)!r} + '/line_reader.py']),
        ExecuteProcess(name='nap', output='screen', cmd=['sleep', '600']),
        ExecuteProcess(name='slow', output='screen',
                       cmd=[sys.executable, {str(PROGRAMS)!r} + '/slow_stop_reader.py']),
    ])
"""


PIPED_TWO = re.sub(r"        ExecuteProcess\(name='slow'.*?\]\),\n", "", PIPED, flags=re.S)
"""PIPED without the node slow to stop (which only test_interact_tui's restarts need)."""


def test_a_node_with_pipes_is_restarted_with_a_terminal_to_type_into_until_a_plain_restart(
        write):
    """As ros2 launch, a process without emulate_tty gets pipes: a keyboard node refuses
    them, as teleop_twist_keyboard does, and one that runs cannot be typed into. `restart
    --terminal` (what the TUI's `i` offers) gives it a terminal; a plain restart takes it
    back."""
    name = start_here(str(write(PIPED_TWO)))
    wait_state(name, "lines-1", "failed")
    assert "stdin is not a terminal" in logs(name, "lines-1")
    assert process(name, "lines-1")["terminal"] is False
    wait_state(name, "nap-2", "running")
    typist = Link(name)
    try:
        with pytest.raises(SessionError, match="nap-2 cannot be typed into: it has no "
                           "terminal: it was started with pipes"):
            typist.request(TakeKeys(process="nap-2", on=True))
        assert tl("restart", name, "lines-1", "--terminal").stdout == "lines-1: running\n"
        assert process(name, "lines-1")["terminal"] is True
        wait_for(lambda: "ready" in logs(name, "lines-1"), what="the reader ready")
        typist.request(TakeKeys(process="lines-1", on=True))
        typist.request(Input(process="lines-1", data="hello robot\r"))
        wait_for(lambda: "got: hello robot" in logs(name, "lines-1"), what="the typed line")
        typist.request(TakeKeys(process="lines-1", on=False))
        tl("restart", name, "lines-1", check=False)
        wait_state(name, "lines-1", "failed")
        assert process(name, "lines-1")["terminal"] is False
        assert logs(name, "lines-1").count("stdin is not a terminal") == 2
    finally:
        typist.close()
    stop_here(name)


def test_a_segfault_is_failed_in_status_and_wait_with_its_signal(shared):
    name = shared
    wait_state(name, "segv-3", "failed")
    crashed = next(p for p in cli_status(name)["processes"] if p["id"] == "segv-3")
    assert crashed["state"] == "failed"
    assert crashed["signal"] == "SIGSEGV"
    assert "killed by SIGSEGV" in crashed["detail"]
    # waiting for a clean end of a process that crashed: one line, at once, status 1
    waited = run_cli("wait", name, "segv-3", "exited", "--timeout", "60")
    assert waited.returncode == 1
    assert "segv-3 failed, not exited: killed by SIGSEGV" in waited.stderr
    # the exact command, pasted into a shell, runs the same program with the same env
    assert crashed["command"][1].endswith("segv.py")
    assert crashed["env"]["CRASH_NOTE"] == "a b"
    by_hand = subprocess.run(["sh", "-c", crashed["command_line"]], capture_output=True,
                             text=True, timeout=60)
    assert by_hand.returncode == -11 or by_hand.returncode == 139
    assert "about to crash" in by_hand.stdout


def test_a_non_zero_exit_nobody_asked_for_is_failed_and_a_stop_is_not(write):
    """status agrees with headless ("process has died", ERROR), the tree and the exit status."""
    name = start_here(str(write("""
        from launch import LaunchDescription
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            return LaunchDescription([
                ExecuteProcess(name='quits', cmd=['sh', '-c', 'exit 3']),
                ExecuteProcess(name='stays', cmd=['sleep', '600']),
            ])
        """)))
    wait_state(name, "quits-1", "failed")
    quits = process(name, "quits-1")
    assert quits["state"] == "failed" and quits["exit_code"] == 3
    assert "signal" not in quits  # an exit status, not a signal
    wait_state(name, "stays-2", "running")
    link = Link(name)
    try:
        link.request(Stop(process="stays-2"))
    finally:
        link.close()
    wait_state(name, "stays-2", "exited")  # asked for: not a failure
    stop_here(name)


SEGV = f"""
import sys
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='segv', cmd=[sys.executable, {str(PROGRAMS)!r} + '/segv.py'],
                       output='screen'),
    ])
"""
"""The crashing program alone: what the restarts under a tool need."""


@requires_gdb
def test_restart_under_gdb_shows_the_backtrace_then_a_plain_restart_drops_it(
        write, monkeypatch):
    monkeypatch.setenv("DEBUGINFOD_URLS", "")  # no network look-up of debug symbols
    name = start_here(str(write(SEGV)))
    wait_state(name, "segv-1", "failed")
    tl("restart", name, "segv-1", "--prefix", "gdb -q -batch -nx -ex run -ex bt --args",
       check=False)
    wait_for(lambda: "#1 " in logs(name, "segv-1"), what="gdb's backtrace in the log")
    text = logs(name, "segv-1")
    assert "Program received signal SIGSEGV" in text
    assert process(name, "segv-1")["command"][0].endswith("gdb")
    # the next plain restart runs it as the file says
    tl("restart", name, "segv-1", check=False)
    wait_for(lambda: process(name, "segv-1")["state"] == "failed" and
             not process(name, "segv-1")["command"][0].endswith("gdb"),
             what="a plain run that crashes again")
    assert process(name, "segv-1")["signal"] == "SIGSEGV"
    stop_here(name)


def test_a_respawning_node_left_under_a_tool_with_status_0_is_not_brought_back(write):
    """Quitting gdb ends the debugging session, status 0: a respawn=True node does not come
    back under gdb again (the file's own run would: launch respawns any end), and says so."""
    name = start_here(str(write("""
        from launch import LaunchDescription
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            return LaunchDescription([
                ExecuteProcess(name='keeps', respawn=True, respawn_delay=0.2,
                               cmd=['sh', '-c', 'echo keeps up; exec sleep 600'])])
        """)))
    wait_state(name, "keeps-1", "running")
    # `true` stands for the tool the operator leaves: it ends at once, status 0
    tl("restart", name, "keeps-1", "--prefix", "true", check=False)
    wait_for(lambda: "ended under 'true' with status 0: not respawned" in logs(name, "keeps-1"),
             what="the line saying it is not respawned")
    assert process(name, "keeps-1")["state"] == "exited"
    # a plain restart runs it as the file says, and respawns it again as the file says
    tl("restart", name, "keeps-1", check=False)
    wait_state(name, "keeps-1", "running")
    assert not process(name, "keeps-1")["command"][0] == "true"
    stop_here(name)

def test_a_prefix_that_is_not_a_program_changes_nothing(shared):
    name = shared
    before = process(name, "keys-2")
    done = run_cli("restart", name, "keys-2", "--prefix", "no-such-debugger --args")
    assert done.returncode == 2
    assert "'no-such-debugger' is not a program on PATH" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    after = process(name, "keys-2")
    assert after["state"] == "running" and after["pid"] == before["pid"]
    bad_level = run_cli("restart", name, "keys-2", "--log-level", "loud")
    assert bad_level.returncode == 2 and "keys-2 is not a ROS node" in bad_level.stderr
    assert process(name, "keys-2")["pid"] == before["pid"]


NODES = """
from launch import LaunchDescription
from launch_ros.actions import Node
def generate_launch_description():
    return LaunchDescription([
        Node(executable='tl_talker', name='talker'),
        Node(executable='tl_listener', name='listener'),
        Node(executable='tl_listener', name='own', prefix='nice -n 1'),
    ])
"""

TALKER = """
from launch import LaunchDescription
from launch_ros.actions import Node
def generate_launch_description():
    return LaunchDescription([Node(executable='tl_talker', name='talker')])
"""
"""One rclpy node: what the tests of a node's own command line need."""
LISTENER = TALKER.replace("'tl_talker', name='talker'", "'tl_listener', name='listener'")

NODE_PROGRAM = """\
import sys
import rclpy
rclpy.init(args=sys.argv)
node = rclpy.create_node('unnamed')
node.get_logger().debug('a debug line')
node.get_logger().info('ready')
try:
    rclpy.spin(node)
except (KeyboardInterrupt, rclpy.executors.ExternalShutdownException):
    pass
"""


@pytest.fixture
def nodes(tmp_path, monkeypatch) -> None:
    """Two rclpy node programs on PATH, `tl_talker` and `tl_listener` (one text)."""
    folder = tmp_path / "bin"
    folder.mkdir()
    for name in ("tl_talker", "tl_listener"):
        path = folder / name
        path.write_text(f"#!{sys.executable}\n{NODE_PROGRAM}")
        path.chmod(0o755)
    monkeypatch.setenv("PATH", f"{folder}{os.pathsep}{os.environ['PATH']}")


def test_launch_prefix_with_a_filter_shows_in_print_as_ros2_launch_would(write, nodes):
    path = write(NODES)
    done = run_cli(str(path), "--print", "--json", "--launch-prefix", "valgrind --tool=memcheck",
                   "--launch-prefix-filter", "tl_talk")
    assert done.returncode == 0, done.stderr
    plan = json.loads(done.stdout)
    cmds = {p["name"]: p["cmd"] for p in plan["processes"]}
    assert cmds["talker"][:2] == ["valgrind", "--tool=memcheck"]
    assert cmds["talker"][2].endswith("talker")
    assert cmds["listener"][0].endswith("listener")  # the filter does not match it
    assert cmds["own"][:3] == ["nice", "-n", "1"]  # an own prefix wins, alone
    refused = run_cli(str(path), "--print", "--launch-prefix-filter", "tl_talk")
    assert refused.returncode == 2
    assert "--launch-prefix must be given" in refused.stderr
    bad = run_cli(str(path), "--print", "--launch-prefix", "gdb", "--launch-prefix-filter", "(")
    assert bad.returncode == 2 and "is not a regular expression" in bad.stderr


def test_log_level_is_appended_as_ros_args_and_kept_until_changed(write, nodes):
    name = start_here(str(write(TALKER)))
    wait_state(name, "talker-1", "running")
    tl("restart", name, "talker-1", "--log-level", "DEBUG")
    command = process(name, "talker-1")["command"]
    assert command[-3:] == ["--ros-args", "--log-level", "debug"]
    wait_for(lambda: "[DEBUG]" in logs(name, "talker-1"), what="a debug line")
    tl("restart", name, "talker-1")  # a plain restart keeps the level
    assert process(name, "talker-1")["command"][-1] == "debug"
    tl("restart", name, "talker-1", "--log-level", "")  # '' goes back to the file's
    assert "--log-level" not in process(name, "talker-1")["command"]
    stop_here(name)


PROBE = """
import sys, time, rclpy
rclpy.init()
node = rclpy.create_node('probe')
end = time.monotonic() + float(sys.argv[1])
names = []
while '/listener' not in names and time.monotonic() < end:
    time.sleep(0.1)
    names = [ns.rstrip('/') + '/' + nm for nm, ns in node.get_node_names_and_namespaces()]
print(names)
"""
"""Prints the nodes it discovers once /listener is among them (or its time is up)."""


def test_status_command_line_of_a_node_runs_it_by_hand(write, nodes):
    name = start_here(str(write(LISTENER)))
    wait_state(name, "listener-1", "running")
    line = next(p for p in cli_status(name)["processes"]
                if p["id"] == "listener-1")["command_line"]
    assert "__node:=listener" in line
    stop_here(name)
    by_hand = subprocess.Popen(["sh", "-c", line], stdout=subprocess.DEVNULL,
                               stderr=subprocess.STDOUT, start_new_session=True)
    try:
        node_list = subprocess.run([sys.executable, "-c", PROBE, "60"], capture_output=True,
                                   text=True, timeout=120).stdout
        assert "/listener" in node_list
    finally:
        os.killpg(by_hand.pid, signal.SIGKILL)
        by_hand.wait()


def test_headless_keyboard_nodes_get_a_terminal_and_a_crash_is_an_error(write):
    out = run_headless(write(LAUNCH), until=("killed by SIGSEGV", "[lines-1] ready",
                                             "[keys-2] ready"))
    assert "[lines-1] ready" in out and "[keys-2] ready" in out
    assert "stdin is not a terminal" not in out
    assert "[ERROR] [segv-3]: process has died" in out


def test_attach_type_opens_the_tui_typing_into_the_process(shared):
    """`attach NAME --type PROCESS` (what a fleet's `i` runs): the TUI opens typing into
    it, by its name as by its id; ctrl+] gives the keys back."""
    name = shared
    terminal = Terminal("attach", name, "--type", "lines")
    try:
        terminal.read_until(b"typing to lines-1")
        os.write(terminal.master, b"hello there\r")
        wait_for(lambda: "got: hello there" in logs(name, "lines-1"), what="the line typed")
        os.write(terminal.master, b"\x1d")  # ctrl+]: the keys are tuilaunch's again
        assert terminal.press_until_exit(b"d") == 0
    finally:
        terminal.close()
    assert process(name, "lines-1")["state"] == "running"  # d left it running
    wait_for(lambda: status(name)["typing"] is None, what="the keyboard given back")
