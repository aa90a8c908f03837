"""The command line's habits (issue 26, item 8) that no other test file holds, each tried as
a user tries it: real launches, the command run as a shell runs it."""

from __future__ import annotations

import os
import signal

from tuilaunch.client.link import open_link
from tuilaunch.engine.ros.bridge import RosBridge
from tuilaunch.engine.run.session import session_dir
from tuilaunch.engine.run.vocabulary.requests import Apply, Subscribe

from ..conftest import run_cli, wait_for
from .inspector_helpers import eventually, run
from .session_steps import start_here, stop_here
from .test_sessions import Terminal, status, tl, wait_state
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
        # the server's plan wrote the node's parameters (the TUI reads no launch file)
        assert len(list(tmp.glob("tuilaunch-*-params-*"))) == 1
        os.kill(terminal.proc.pid, signal.SIGHUP)  # the ssh link or the tmux pane is gone
        terminal.wait_exit()
    finally:
        terminal.close()
    wait_for(lambda: not session_dir.live_sessions(), what="the launch stopped")
    wait_for(lambda: not list(tmp.glob("tuilaunch-*")),
             what=f"no folder left in $TMPDIR: {list(tmp.iterdir())}")


ROBOT = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('robot', default_value='r1'),
        Node(package='tuilaunch_demos', executable='talker', name='talker',
             namespace=LaunchConfiguration('robot'))])
"""


def dumped(session: str, node: str) -> None:
    """`params --dump` answered, once the node is on the graph (running comes first)."""
    wait_for(lambda: "rate:" in tl("params", session, node, "--dump", check=False).stdout,
             what=f"{node}'s parameters")


def test_a_relaunched_namespace_leaves_no_stale_service_on_the_graph(runtime, write):
    name = start_here(str(write(ROBOT)))
    wait_state(name, "talker-1", "running")
    # the session's bridge calls /r1/talker's parameter services: its clients are made
    dumped(name, "/r1/talker")
    link = open_link(name)
    try:  # what the Args tab's F5 asks: robot:=r2
        link.request(Apply(arguments={"robot": "r2"}))
    finally:
        link.close()
    wait_state(name, "talker-1", "running")
    dumped(name, "/r2/talker")

    async def r1_gone(bridge: RosBridge) -> None:
        async def listed() -> bool:
            services = [s for s, _ in await bridge.list_services()]
            return any(s.startswith("/r2/talker/") for s in services) and not any(
                s.startswith("/r1/") for s in services)
        await eventually(listed, what="no /r1 service listed, /r2/talker's are")

    run(r1_gone)
    stop_here(name)


SAYS = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
from launch.substitutions import LaunchConfiguration
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('word', default_value='hello', description='what it says'),
        ExecuteProcess(cmd=['echo', LaunchConfiguration('word')], name='says',
                       output='screen')])
"""


def test_ros2_launchs_own_option_spellings_work(write):
    """What a ros2 launch user types: `-n` runs without the TUI even in a terminal (ros2
    launch's non-interactive run), `-d` shows the traceback, `--print-description` and
    `--show-arguments` are `-p` and `-s`."""
    path = write(SAYS)
    terminal = Terminal("-n", str(path), "word:=bonjour")
    try:
        terminal.read_until(b"[says-1] bonjour")
        terminal.read_until(b"process has finished cleanly")
        assert terminal.wait_exit() == 0
        assert b"\x1b[?1049h" not in terminal.screen  # the TUI's screen never opened
    finally:
        terminal.close()
    shown = run_cli(str(path), "--print-description", "--json", "word:=salut")
    assert shown.returncode == 0 and "salut" in shown.stdout, shown.stderr
    listed = run_cli(str(path), "--show-arguments")
    assert listed.returncode == 0 and "'word':" in listed.stdout and "what it says" in \
        listed.stdout, listed.stderr
    broken = write("def generate_launch_description():\n    raise RuntimeError('boom')\n")
    debugged = run_cli(str(broken), "-d", "-p")
    assert debugged.returncode != 0 and "Traceback" in debugged.stderr


PRINTS = """
import json
import os
import sys
from launch import LaunchDescription
from launch.actions import ExecuteProcess, OpaqueFunction, RegisterEventHandler, TimerAction
from launch.event_handlers import OnProcessStart

def said(event, context):
    print('robot is', 'up', flush=True)

def later(context):
    print('timer fired')
    print('and a second line')
    # code that uses the stream itself, as a subprocess given sys.stdout does
    print('stdout is', sys.stdout.encoding.lower(), os.fstat(sys.stdout.fileno()).st_mode > 0)

def generate_launch_description():
    napper = ExecuteProcess(cmd=['sleep', '600'], name='napper')
    return LaunchDescription([napper,
        RegisterEventHandler(OnProcessStart(target_action=napper, on_start=said)),
        TimerAction(period=0.5, actions=[OpaqueFunction(function=later)])])
"""


def test_what_launch_code_prints_in_a_session_is_a_line_every_client_sees(runtime, write):
    """print() in an event callback or a timer's OpaqueFunction, which ros2 launch shows on
    its terminal: a session has none, so each line is a launch line, in every client's
    all-nodes pane (the TUI runs its launch as a session too) and in launch.log."""
    name = start_here(str(write(PRINTS)))

    def said() -> set[str]:
        link = open_link(name)
        try:
            recent = link.request(Subscribe(max_lines=1))["recent"]
        finally:
            link.close()
        return {e.get("reason") for e in recent
                if e.get("kind") == "log" and e.get("process") is None}

    try:
        wait_for(lambda: {"robot is up", "timer fired", "and a second line",
                          "stdout is utf-8 True"} <= said(),
                 what="the printed lines among the session's launch lines")
    finally:
        stop_here(name)


UNNAMED = """
from launch import LaunchDescription
from launch_ros.actions import Node
def generate_launch_description():
    return LaunchDescription([Node(package='tuilaunch_demos', executable='talker',
                                   namespace='r2', parameters=[{'rate': 5.0}])])
"""


def test_a_restart_at_debug_level_keeps_the_name_the_node_reports(runtime, write):
    """At debug level rcl speaks first (`[rcl]: Initializing node ...`): the node a process
    runs is still known by its own logger's name, not /rcl (issue 36, item 4)."""
    name = start_here(str(write(UNNAMED)))
    try:
        wait_state(name, "talker-1", "running")
        dumped(name, "talker-1")
        tl("restart", name, "talker-1", "--log-level", "debug")
        wait_state(name, "talker-1", "running")
        wait_for(lambda: "[rcl]: " in tl("logs", name, "talker-1").stdout,
                 what="rcl's debug lines, before the node's own")
        dumped(name, "talker-1")
    finally:
        stop_here(name)


def killed(pid: int) -> bool:
    """Gone, or a zombie its parent has not reaped yet (it may be reaped while we read)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] == "Z"
    except FileNotFoundError:
        return True


def test_the_parameter_folder_of_a_killed_server_is_removed_by_the_next_start(
        runtime, write, tmp_path, monkeypatch):
    """`kill -9` of a session server leaves its folder in $TMPDIR (no atexit runs): the
    next tuilaunch that plans removes it (issue 36, item 15)."""
    tmp = tmp_path / "tmp"
    tmp.mkdir()
    monkeypatch.setenv("TMPDIR", str(tmp))
    launch = str(write(TALKER))
    name = start_here(launch)
    wait_state(name, "talker-1", "running")
    pid = status(name)["pid"]
    left = list(tmp.glob(f"tuilaunch-{pid}-params-*"))
    assert len(left) == 1
    os.kill(pid, signal.SIGKILL)
    wait_for(lambda: killed(pid), what="the server killed")
    assert left[0].is_dir()  # nothing ran its cleanup
    again = tl(launch, "--detach").stdout.strip()  # the command plans: the subject
    try:
        assert not left[0].exists()
    finally:
        stop_here(again)
