"""What a file puts in event handlers, timers and OnShutdown happens when the event does:
`--print` describes it and runs nothing; a headless run performs it in launch's order."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from ..conftest import plan_of, run_cli, run_headless
from .launch_world import make_package, probe_records, world_env

HEADER = """
import os
from launch import LaunchDescription
from launch.actions import (DeclareLaunchArgument, EmitEvent, ExecuteProcess, GroupAction,
                            LogInfo, OpaqueFunction, RegisterEventHandler, Shutdown,
                            TimerAction)
from launch.event_handlers import (OnExecutionComplete, OnProcessExit, OnProcessIO,
                                   OnProcessStart, OnShutdown)
from launch.events import matches_action
from launch.events.process import ShutdownProcess
from launch.substitutions import EnvironmentVariable, LaunchConfiguration, LocalSubstitution
from launch_ros.actions import Node
"""


def world(tmp_path, **more_env: str):
    """The fake_robot package's environment (with `more_env`, e.g. how long a probe lives) and
    the folder its probes report into."""
    prefix = tmp_path / "prefix"
    make_package(prefix, "fake_robot", ["driver", "spawner", "rviz2", "sleeper"])
    probes = tmp_path / "probes"
    probes.mkdir()
    return {**world_env(prefix, tmp_path, probes), **more_env}, probes


def headless(path, env, *args, timeout=120):
    return run_cli(str(path), "--headless", *args, env=env, timeout=timeout)


def lines_of(done) -> list[str]:
    return [line for line in done.stdout.splitlines()
            if "All log files" not in line and "Default logging verbosity" not in line]


def index_of(lines: list[str], needle: str) -> int:
    for i, line in enumerate(lines):
        if needle in line:
            return i
    raise AssertionError(f"{needle!r} not in output:\n" + "\n".join(lines))


def test_on_shutdown_cleanup_runs_when_the_launch_ends_and_never_at_print(write, tmp_path):
    env, _ = world(tmp_path)
    marker = tmp_path / "world.sdf"
    path = write(HEADER + f"""
def generate_launch_description():
    world = '{marker}'
    with open(world, 'w') as handle:
        handle.write('<sdf/>')
    return LaunchDescription([
        Node(package='fake_robot', executable='driver', name='driver'),
        RegisterEventHandler(OnShutdown(on_shutdown=[
            OpaqueFunction(function=lambda _: os.remove(world)),
            LogInfo(msg=['bye: ', LocalSubstitution('event.reason')])])),
    ])
""")
    printed = run_cli(str(path), "--print", env=env)
    assert printed.returncode == 0, printed.stderr
    assert marker.exists()  # --print never runs event-time code
    assert "at event time" in printed.stdout
    done = headless(path, env)
    assert done.returncode == 0, done.stderr
    assert not marker.exists()
    lines = lines_of(done)
    assert index_of(lines, "driver-1]: process has finished") < index_of(lines, "bye: idle")


def test_on_exit_of_node_and_process_and_handlers_without_target(write, tmp_path):
    env, _ = world(tmp_path)
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        Node(package='fake_robot', executable='driver', name='driver',
             on_exit=[LogInfo(msg='driver done')]),
        ExecuteProcess(cmd=['true'], name='helper', on_exit=LogInfo(msg='helper done')),
        RegisterEventHandler(OnProcessExit(on_exit=[
            LogInfo(msg=['exited: ', LocalSubstitution('event.process_name')])])),
        RegisterEventHandler(OnProcessIO(on_stdout=lambda event: LogInfo(
            msg='heard ' + event.text.decode().strip()))),
    ])
""")
    done = headless(path, env)
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert "driver done" in out and "helper done" in out
    assert "exited: driver-1" in out and "exited: helper-2" in out
    assert "heard driver up" in out
    lines = lines_of(done)
    assert index_of(lines, "driver-1]: process has finished") < index_of(lines, "driver done")


def test_exit_handlers_fire_when_shutdown_stops_their_target(write, tmp_path):
    env, _ = world(tmp_path, PROBE_SECONDS="60")
    path = write(HEADER + """
def generate_launch_description():
    driver = Node(package='fake_robot', executable='driver', name='driver')
    return LaunchDescription([
        driver,
        RegisterEventHandler(OnProcessStart(target_action=driver, on_start=[
            TimerAction(period=0.3, actions=[EmitEvent(event=Shutdown(reason='enough'))])])),
        RegisterEventHandler(OnProcessExit(target_action=driver, on_exit=[
            LogInfo(msg=['driver stopped with ', LocalSubstitution('event.returncode')])])),
        RegisterEventHandler(OnExecutionComplete(target_action=driver, on_completion=[
            LogInfo(msg='driver complete')])),
    ])
""")
    done = headless(path, env)
    lines = lines_of(done)
    stop = index_of(lines, "[INFO] [driver-1]: process stopped")  # a stop, not a crash
    assert index_of(lines, "sending signal 'SIGINT' to process[driver-1]") < stop < \
        index_of(lines, "driver stopped with")
    assert "driver complete" in done.stdout


def test_a_substitution_failing_only_in_an_event_branch_does_not_stop_the_load(write, tmp_path):
    env, _ = world(tmp_path)
    env.pop("TUILAUNCH_SURELY_UNSET", None)
    side_effect = tmp_path / "ran.txt"
    path = write(HEADER + f"""
def touch(context):
    open('{side_effect}', 'w').close()
    return [LogInfo(msg='touched by ' + context.locals.event.process_name)]

def generate_launch_description():
    driver = Node(package='fake_robot', executable='driver', name='driver')
    return LaunchDescription([
        driver,
        RegisterEventHandler(OnProcessExit(target_action=driver, on_exit=[
            LogInfo(msg=EnvironmentVariable('TUILAUNCH_SURELY_UNSET')),
            Node(package='fake_robot', executable='rviz2', name='rviz'),
        ])),
        RegisterEventHandler(OnProcessStart(target_action=driver, on_start=[
            OpaqueFunction(function=touch)])),
    ])
""")
    plan = plan_of(path)
    assert not side_effect.exists()
    kinds = [a.kind for a in plan.actions]
    assert kinds == ["deferred", "deferred"]
    rviz = [p for p in plan.processes if p.name == "rviz"]
    assert rviz and rviz[0].trigger is not None and rviz[0].trigger.on == "exit"
    done = headless(path, env)
    assert side_effect.exists()
    out = done.stdout
    assert "touched by driver-1" in out
    assert "environment variable 'TUILAUNCH_SURELY_UNSET' is not set" in out
    assert "[rviz2-" in out or "rviz-" in out  # the rest of the handler still ran


def test_spawner_chain_runs_in_launch_order(write, tmp_path):
    env, probes = world(tmp_path)
    path = write(HEADER + """
def generate_launch_description():
    driver = Node(package='fake_robot', executable='driver', name='control_node')
    jsb = Node(package='fake_robot', executable='spawner',
               arguments=['joint_state_broadcaster', '--controller-manager',
                          '/controller_manager'])
    controller = Node(package='fake_robot', executable='spawner',
                      arguments=['forward_position_controller', '--param-file', 'x.yaml'])
    rviz = Node(package='fake_robot', executable='rviz2', name='rviz2',
                arguments=['-d', 'view.rviz'])
    return LaunchDescription([
        driver, jsb,
        RegisterEventHandler(OnProcessExit(target_action=jsb, on_exit=[rviz])),
        RegisterEventHandler(OnProcessExit(target_action=jsb, on_exit=[controller])),
    ])
""")
    done = headless(path, env)
    assert done.returncode == 0, done.stderr
    lines = lines_of(done)
    jsb_exit = index_of(lines, "[spawner-2]: process has finished")
    assert jsb_exit < index_of(lines, "[rviz2-3]: process started")
    assert jsb_exit < index_of(lines, "[spawner-4]: process started")
    argvs = sorted(r["argv"][0] for r in probe_records(probes) if r["exe"] == "spawner")
    assert argvs == ["forward_position_controller", "joint_state_broadcaster"]


def test_shutdown_process_event_stops_only_its_target(write, tmp_path):
    env, _ = world(tmp_path, PROBE_SECONDS_SLEEPER="60")
    path = write(HEADER + """
def generate_launch_description():
    sleeper = Node(package='fake_robot', executable='sleeper', name='sleeper')
    driver = Node(package='fake_robot', executable='driver', name='driver')
    return LaunchDescription([
        sleeper, driver,
        RegisterEventHandler(OnProcessExit(target_action=driver, on_exit=[
            EmitEvent(event=ShutdownProcess(process_matcher=matches_action(sleeper)))])),
    ])
""")
    done = headless(path, env, timeout=120)
    lines = lines_of(done)
    assert index_of(lines, "[driver-2]: process has finished") < index_of(
        lines, "[INFO] [sleeper-1]: process stopped")
    assert done.returncode != 0 or "killed by SIGINT" in done.stdout or "exit code" in done.stdout


SIGNALLED = HEADER + """
import signal
from launch.events.process import SignalProcess

def generate_launch_description():
    # the listener answers SIGUSR1 and ends (the driver ends once its trap is set); the
    # stubborn one ignores SIGTERM
    ready = LaunchConfiguration('ready')
    listener = ExecuteProcess(name='listener', output='screen', cmd=['sh', '-c',
        'trap "echo got USR1; exit 0" USR1; touch "$0"; while :; do sleep 0.1; done', ready])
    stubborn = ExecuteProcess(name='stubborn', output='screen', cmd=['sh', '-c',
        'trap "" TERM; echo holding; while :; do sleep 0.1; done'])
    driver = ExecuteProcess(name='driver', cmd=['sh', '-c',
        'while [ ! -e "$0" ]; do sleep 0.05; done', ready])
    return LaunchDescription([
        DeclareLaunchArgument('ready'), listener, stubborn, driver,
        RegisterEventHandler(OnProcessExit(target_action=driver, on_exit=[
            EmitEvent(event=SignalProcess(signal_number=signal.SIGUSR1,
                                          process_matcher=matches_action(listener))),
            EmitEvent(event=SignalProcess(signal_number='SIGKILL',
                                          process_matcher=matches_action(stubborn)))])),
    ])
"""


def test_signal_process_event_sends_its_signal_to_its_target_only(write, tmp_path):
    """launch's SignalProcess: the signal goes to the matched process, said in launch's
    words; SIGKILL may be given as the string launch takes."""
    path = write(SIGNALLED)
    done = headless(path, {}, f"ready:={tmp_path / 'ready'}", timeout=120)
    lines = lines_of(done)
    driver_done = index_of(lines, "[driver-3]: process has finished cleanly")
    sent = index_of(lines, "[INFO] [listener-1]: sending signal 'SIGUSR1' to process[listener-1]")
    assert driver_done < sent < index_of(lines, "[listener-1] got USR1")
    assert sent < index_of(lines, "[listener-1]: process has finished cleanly")
    assert driver_done < index_of(
        lines, "[INFO] [stubborn-2]: sending signal 'SIGKILL' to process[stubborn-2]")
    assert "[ERROR] [stubborn-2]: process has died" in done.stdout
    assert "exit code -9" in done.stdout


def test_signal_process_with_no_signal_is_one_line_with_its_line(write):
    path = write(HEADER + """
from launch.events.process import SignalProcess

def generate_launch_description():
    p = ExecuteProcess(cmd=['true'])
    return LaunchDescription([p, EmitEvent(event=SignalProcess(
        signal_number=10, process_matcher=matches_action(p)))])
""")
    done = run_cli(str(path), "--print")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert f"{path}:" in done.stderr and "signal_number must be a signal" in done.stderr


COROUTINES = """
import asyncio
from pathlib import Path
from launch import LaunchDescription
from launch.actions import (DeclareLaunchArgument, ExecuteProcess, OpaqueCoroutine,
                            RegisterEventHandler)
from launch.event_handlers import OnExecutionComplete
from launch.substitutions import LaunchConfiguration


async def wait_for_file(context):
    path = Path(LaunchConfiguration('flag').perform(context))
    while not path.exists():
        await asyncio.sleep(0.05)
    print('the flag is up', flush=True)


async def broken(word):
    await asyncio.sleep(0.1)
    raise RuntimeError(word)


def start_user(event, context):
    return ExecuteProcess(cmd=['echo', 'user started'], name='user', output='screen')


def generate_launch_description():
    waiting = OpaqueCoroutine(coroutine=wait_for_file)
    failing = OpaqueCoroutine(coroutine=broken, args=['no socket'], ignore_context=True)
    return LaunchDescription([
        DeclareLaunchArgument('flag'),
        RegisterEventHandler(OnExecutionComplete(target_action=waiting,
                                                 on_completion=start_user)),
        ExecuteProcess(name='maker', output='screen', cmd=[
            'sh', '-c', 'sleep 1; touch "$0"; echo touched', LaunchConfiguration('flag')]),
        waiting, failing,
    ])
"""


def test_an_opaque_coroutine_runs_on_the_loop_and_its_completion_is_an_event(write,
                                                                           tmp_path):
    """launch's OpaqueCoroutine, as a telegraf bringup uses it: wait on the loop for what a
    node makes, then start the next program from OnExecutionComplete. One that raises is
    its own error, with its line; the launch goes on."""
    path = write(COROUTINES)
    done = headless(path, {}, f"flag:={tmp_path / 'flag'}", timeout=120)
    lines = lines_of(done)
    # the maker's "touched" and the coroutine's line race (the file is there before the
    # maker's line is read from its terminal): either may come first, on a busy machine too
    assert index_of(lines, "[maker-1] touched") >= 0
    assert index_of(lines, "[maker-1]: process started") < index_of(
        lines, "the flag is up") < index_of(
        lines, "[user-2]: process started") < index_of(lines, "[user-2] user started")
    error = lines[index_of(lines, "coroutine broken")]
    assert "[ERROR]" in error and "raised RuntimeError: no socket" in error
    assert f"{path}:20" in error, error  # the line that raised
    assert done.returncode == 1  # an action failed


def test_a_shutdown_cancels_a_coroutine_and_a_function_is_refused(write):
    path = write("""
import asyncio
from launch import LaunchDescription
from launch.actions import OpaqueCoroutine


async def forever():
    print('watching', flush=True)
    try:
        await asyncio.sleep(600)
    except asyncio.CancelledError:
        print('coroutine cancelled', flush=True)
        raise


def generate_launch_description():
    return LaunchDescription([OpaqueCoroutine(coroutine=forever, ignore_context=True)])
""")
    # nothing else runs: the launch stays up for the coroutine, until Ctrl+C cancels it
    assert "coroutine cancelled" in run_headless(path, until=("watching",))
    plain = write("""
from launch import LaunchDescription
from launch.actions import OpaqueCoroutine
def later():
    pass
def generate_launch_description():
    return LaunchDescription([OpaqueCoroutine(coroutine=later)])
""")
    refused = run_cli(str(plain), "--print")
    assert refused.returncode == 2 and "Traceback" not in refused.stderr
    assert f"{plain}:7" in refused.stderr and "coroutine function (async def)" in \
        refused.stderr


def test_a_file_with_only_a_log_line_prints_it(write, tmp_path):
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([LogInfo(msg='nothing to run today')])
""")
    done = headless(path, {})
    assert done.returncode == 0, done.stderr
    assert "nothing to run today" in done.stdout


def test_group_without_forwarding_sees_only_what_it_is_given(write):
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('outer', default_value='out'),
        GroupAction([LogInfo(msg=[LaunchConfiguration('given'), ' ',
                                  LaunchConfiguration('outer', default='hidden')])],
                    forwarding=False,
                    launch_configurations={'given': LaunchConfiguration('outer')}),
        LogInfo(msg=LaunchConfiguration('outer')),
    ])
""")
    assert [a.data for a in plan_of(path).actions] == ["out hidden", "out"]


def test_print_json_keeps_stdout_pure_and_a_closed_pipe_is_quiet(write, tmp_path):
    path = write(HEADER + """
print('robot model: burger')

def generate_launch_description():
    print('generating')
    return LaunchDescription([LogInfo(msg='x')] * 1 + [
        Node(package='tuilaunch_demos', executable='talker', name=f'talker{i}')
        for i in range(300)])
""")
    done = run_cli(str(path), "--print", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["processes"][0]["name"] == "talker0"
    assert "robot model: burger" in done.stderr and "generating" in done.stderr
    shell = subprocess.run(
        f"{sys.executable} -m tuilaunch {path} --print | head -1", shell=True,
        capture_output=True, text=True, timeout=60, env=os.environ)
    assert shell.stdout.count("\n") == 1
    assert "Traceback" not in shell.stderr and "BrokenPipe" not in shell.stderr


def test_timer_opaque_function_runs_when_the_timer_fires(write, tmp_path):
    env, probes = world(tmp_path)
    path = write(HEADER + """
def later(context):
    return [Node(package='fake_robot', executable='rviz2', name='late_' +
                 context.launch_configurations['robot'])]

def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('robot', default_value='r1'),
        Node(package='fake_robot', executable='driver', name='driver'),
        TimerAction(period=0.2, actions=[OpaqueFunction(function=later)]),
    ])
""")
    plan = plan_of(path, robot="r9")
    assert [p.name for p in plan.processes] == ["driver"]  # the function has not run
    done = headless(path, env, "robot:=r9")
    assert done.returncode == 0, done.stdout + done.stderr
    late = [r for r in probe_records(probes) if r["exe"] == "rviz2"]
    assert len(late) == 1 and "__node:=late_r9" in late[0]["argv"]


def test_event_values_show_as_placeholders_in_the_plan(write):
    path = write(HEADER + """
def generate_launch_description():
    p = ExecuteProcess(cmd=['true'], name='job')
    return LaunchDescription([p, RegisterEventHandler(OnProcessExit(target_action=p, on_exit=[
        LogInfo(msg=['code ', LocalSubstitution('event.returncode')])]))])
""")
    assert plan_of(path).actions[0].data == "code <event.returncode>"
