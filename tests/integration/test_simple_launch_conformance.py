"""Where simple_launch files behave as under ros2 launch (simple_launch 1.9 sources).

simple_launch runs `call_service` as a node (`simple_launch/scripts/call_service`): when the
launch stops, that node is stopped like any other and its OnProcessExit handlers run;
its own messages at load time are printed by `console.info` / `console.warn` as
`[simple_launch]: message` in colour.
"""

from __future__ import annotations

import time

from tuilaunch.engine.run.supervisor.ending import ACTION_STOP_S

from ..conftest import plan_of, run_cli, run_headless


def test_a_call_service_stopped_by_the_shutdown_still_fires_its_exit_handlers(write):
    path = write("""
from simple_launch import SimpleLauncher
from simple_launch.events import When, OnProcessExit
from launch.actions import ExecuteProcess

def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo up; sleep 600'], name='plain',
                                 output='screen'))
    call = sl.call_service('/nobody/answers')
    with sl.group(when=When(call, OnProcessExit)):
        sl.log_info('the call is over')
    return sl.launch_description()
""")
    out = run_headless(path, until=("[plain-1] up", "waiting for service /nobody/answers"))
    assert "[INFO] [launch.user]: the call is over" in out.splitlines(), out


def test_a_call_service_alone_stopped_by_ctrl_c_still_fires_its_exit_handlers(write):
    """With no process still stopping to keep the run going, the handlers ran only by
    chance: the run ended before the cancelled call had finished."""
    path = write("""
from simple_launch import SimpleLauncher
from simple_launch.events import When, OnProcessExit

def generate_launch_description():
    sl = SimpleLauncher()
    call = sl.call_service('/nobody/answers')
    with sl.group(when=When(call, OnProcessExit)):
        sl.log_info('the call is over')
    return sl.launch_description()
""")
    for _ in range(3):  # it lost the race most of the time, not always
        out = run_headless(path, until=("waiting for service /nobody/answers",))
        assert "[INFO] [launch.user]: the call is over" in out.splitlines(), out


GREEN, YELLOW, END = "\x1b[92m", "\x1b[93m", "\x1b[0m"


def test_use_sim_time_auto_says_what_it_decided_as_simple_launch_does(write):
    path = write("""
from simple_launch import SimpleLauncher

def generate_launch_description():
    sl = SimpleLauncher(use_sim_time='auto')
    sl.node('tuilaunch_demos', 'talker')
    return sl.launch_description()
""")
    found = run_cli(str(path), "--print", env={"TUILAUNCH_SIM_TIME": "1"})
    assert f"{GREEN}[simple_launch]: SimpleLauncher(use_sim_time='auto'): found a /clock " \
        f"topic, forwarding use_sim_time:=True to all nodes{END}" in found.stdout.splitlines()
    none = run_cli(str(path), "--print", env={"TUILAUNCH_SIM_TIME": "0"})
    assert f"{GREEN}[simple_launch]: SimpleLauncher(use_sim_time='auto'): no /clock topic " \
        f"found, forwarding use_sim_time:=False to all nodes{END}" in none.stdout.splitlines()
    listed = run_cli(str(path), "--show-args")
    assert f"{YELLOW}[simple_launch]: This launch file will forward use_sim_time to all " \
        f"nodes if /clock is advertized at the time of the launch{END}" \
        in listed.stdout.splitlines()


XACRO = """<?xml version="1.0"?>
<robot name="bot" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:arg name="colour" default="red"/>
  <link name="base_$(arg colour)"/>
</robot>
"""


def test_robot_description_in_an_opaque_function_is_folded_as_elsewhere(write, tmp_path):
    (tmp_path / "bot.xacro").write_text(XACRO)
    body = f"""
    sl.robot_state_publisher(description_file={str(tmp_path / 'bot.xacro')!r},
                             xacro_args={{'colour': 'blue'}})
"""
    plain = write("from simple_launch import SimpleLauncher\n"
                  "def generate_launch_description():\n    sl = SimpleLauncher()\n"
                  + body + "    return sl.launch_description()\n", "plain_launch.py")
    opaque = write("from simple_launch import SimpleLauncher\nsl = SimpleLauncher()\n"
                   "def setup():\n" + body +
                   "    return sl.launch_description()\n"
                   "generate_launch_description = sl.launch_description("
                   "opaque_function=setup)\n", "opaque_launch.py")
    described = [plan_of(path).processes[0].parameters["robot_description"]
                 for path in (plain, opaque)]
    assert described[0] == described[1]
    assert "\n" not in described[0] and "base_blue" in described[0]


def test_once_ctrl_c_began_an_exit_group_logs_but_starts_no_call(write):
    """launch starts nothing once shutdown has begun (ExecuteLocal.execute returns at once
    when `context.is_shutdown`), and simple_launch's `set_parameters` and `call_service`
    are nodes: in the OnProcessExit group of a node that Ctrl+C stops they never run, while
    the `log_info` beside them is performed (LogInfo is no process) and logged."""
    path = write("""
from simple_launch import SimpleLauncher
from simple_launch.events import When, OnProcessExit

def generate_launch_description():
    sl = SimpleLauncher()
    talker = sl.node('tuilaunch_demos', 'talker', name='talker')
    with sl.group(when=When(talker, OnProcessExit)):
        sl.log_info('talker is gone')
        sl.set_parameters('talker', {'rate': 2.0})
        sl.call_service('/talker/reset')
    return sl.launch_description()
""")
    started = time.monotonic()
    out = run_headless(path, until=("Publishing:",))
    took = time.monotonic() - started
    lines = out.splitlines()
    assert "[INFO] [launch.user]: talker is gone" in lines, out
    # neither is performed: no wait for the node or the service, no line of theirs
    assert not [line for line in lines if "set_parameters" in line or "call_service" in line
                or "waiting for" in line], out
    assert took < ACTION_STOP_S + 20, (took, out)
