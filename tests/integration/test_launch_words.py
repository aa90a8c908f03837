"""The words a headless run prints where ros2 launch prints them, per launch's sources.

- LogInfo logs with `launch.logging.get_logger('launch.user')` (launch/actions/log_info.py):
  `[INFO] [launch.user]: message`, on screen and in the launch's log file.
- LaunchService's SIGINT handler shuts down with reason `ctrl-c (SIGINT)`; `idle` when
  nothing is left; a `Shutdown()` action's event carries its reason (`reason not given` by
  default) and is emitted again when the launch already stops, so OnShutdown handlers see
  each (launch/launch_service.py, launch/actions/shutdown_action.py).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys

import pytest

from ..conftest import run_cli, run_headless, wait_for

HEADER = """
import os
from launch import LaunchDescription
from launch.actions import (EmitEvent, ExecuteProcess, LogInfo, RegisterEventHandler,
                            Shutdown)
from launch.event_handlers import OnProcessExit, OnShutdown
from launch.events import Shutdown as ShutdownEvent
from launch.substitutions import LocalSubstitution
"""

ON_SHUTDOWN = """
        RegisterEventHandler(OnShutdown(on_shutdown=[
            LogInfo(msg=['shutdown because: ', LocalSubstitution('event.reason')])])),
"""


def test_log_info_speaks_as_launch_user_on_screen_and_in_the_log_file(write, tmp_path):
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([LogInfo(msg='hello from the file')])
""")
    log_root = tmp_path / "logs"
    done = run_cli(str(path), "--headless", env={"ROS_LOG_DIR": str(log_root)})
    assert "[INFO] [launch.user]: hello from the file" in done.stdout.splitlines(), done.stdout
    # ros2 launch's first two lines, in its order
    assert done.stdout.splitlines()[:2] == [
        f"[INFO] [launch]: All log files can be found below {next(log_root.glob('*'))}",
        "[INFO] [launch]: Default logging verbosity is set to INFO"], done.stdout
    launch_log = next(log_root.glob("*-tuilaunch-*")) / "launch.log"
    assert "[INFO] [launch.user]: hello from the file" in launch_log.read_text()


def test_this_launch_file_dir_in_a_log_line_is_where_launch_s_locals_hold_it(write, tmp_path):
    """LogInfo performs its message when it runs. Launch's locals hold the file while it is
    visited (a group, an OpaqueFunction's return) and in a TimerAction's actions (it keeps
    the locals it was executed with), not in what an event handler returns, where
    ThisLaunchFileDir raises "used outside of a launch file": that action alone fails."""
    path = write(HEADER + """
from launch.actions import GroupAction, OpaqueFunction, TimerAction
from launch.substitutions import ThisLaunchFileDir

def generate_launch_description():
    done = ExecuteProcess(cmd=['true'], name='done')
    return LaunchDescription([
        GroupAction([LogInfo(msg=['group: ', ThisLaunchFileDir()])]),
        OpaqueFunction(function=lambda context: [
            LogInfo(msg=['opaque: ', ThisLaunchFileDir()])]),
        TimerAction(period=0.2, actions=[LogInfo(msg=['timer: ', ThisLaunchFileDir()])]),
        done,
        RegisterEventHandler(OnProcessExit(target_action=done, on_exit=[
            LogInfo(msg=['handler: ', ThisLaunchFileDir()]), LogInfo(msg='handler goes on')])),
    ])
""")
    done = run_cli(str(path), "--headless", env={"ROS_LOG_DIR": str(tmp_path / "logs")})
    lines = done.stdout.splitlines()
    folder = str(path.parent)
    for where in ("group", "opaque", "timer"):
        assert f"[INFO] [launch.user]: {where}: {folder}" in lines, done.stdout
    failed = [line for line in lines if "used outside of a launch file" in line]
    assert len(failed) == 1 and failed[0].startswith("[ERROR] ["), done.stdout
    line = next(n for n, text in enumerate(path.read_text().splitlines(), 1)
                if "'handler: '" in text)  # the failed LogInfo's own line
    assert f"{path.name}:{line}: ThisLaunchFileDir used outside of a launch file" in failed[0]
    assert "[INFO] [launch.user]: handler goes on" in lines, done.stdout
    assert done.returncode == 1  # an action failed (ros2 launch stops there, with 1 too)


def test_simple_launch_log_info_speaks_as_launch_user(write):
    path = write("""
from simple_launch import SimpleLauncher

def generate_launch_description():
    sl = SimpleLauncher()
    sl.log_info('from simple_launch')
    return sl.launch_description()
""")
    done = run_cli(str(path), "--headless")
    assert "[INFO] [launch.user]: from simple_launch" in done.stdout.splitlines(), done.stdout


def test_ctrl_c_is_the_reason_on_shutdown_handlers_see(write):
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(cmd=['sleep', '60'], name='sleeper'),""" + ON_SHUTDOWN + """
    ])
""")
    out = run_headless(path, until=("process started",))
    assert "[WARNING] [launch]: user interrupted with ctrl-c (SIGINT)" in out.splitlines(), out
    assert "[INFO] [launch.user]: shutdown because: ctrl-c (SIGINT)" in out.splitlines(), out


def test_idle_and_a_shutdown_action_pass_their_reasons(write):
    idle = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(cmd=['true']),""" + ON_SHUTDOWN + """])
""", "idle_launch.py")
    done = run_cli(str(idle), "--headless")
    assert "[INFO] [launch.user]: shutdown because: idle" in done.stdout.splitlines()

    given = write(HEADER + """
def generate_launch_description():
    quick = ExecuteProcess(cmd=['true'], name='quick')
    return LaunchDescription([
        ExecuteProcess(cmd=['sleep', '60'], name='sleeper'),
        quick,
        RegisterEventHandler(OnProcessExit(target_action=quick, on_exit=[
            Shutdown(reason='quick is done')])),
        RegisterEventHandler(OnProcessExit(target_action=quick, on_exit=[
            EmitEvent(event=ShutdownEvent())])),""" + ON_SHUTDOWN + """
    ])
""", "given_launch.py")
    done = run_cli(str(given), "--headless")
    lines = done.stdout.splitlines()
    assert "[INFO] [launch]: process[quick-2] was required: shutting down launched system" \
        in lines, done.stdout
    # both Shutdown events reach the handler, in the order they were emitted
    reasons = [line for line in lines if "shutdown because" in line]
    assert reasons == ["[INFO] [launch.user]: shutdown because: quick is done",
                       "[INFO] [launch.user]: shutdown because: reason not given"], lines


def test_a_shutdown_emitted_while_stopping_is_seen_again(write, tmp_path):
    """An exit handler of a process the first shutdown stopped emits Shutdown (a viewer's
    `Shutdown(reason='Window closed')`): OnShutdown handlers see that reason too."""
    path = write(HEADER + """
def generate_launch_description():
    viewer = ExecuteProcess(cmd=['sleep', '60'], name='viewer')
    return LaunchDescription([
        viewer,
        RegisterEventHandler(OnProcessExit(target_action=viewer, on_exit=[
            Shutdown(reason='Window closed')])),""" + ON_SHUTDOWN + """
    ])
""")
    out = run_headless(path, until=("process started",)).splitlines()
    reasons = [line for line in out if "shutdown because" in line]
    assert reasons == ["[INFO] [launch.user]: shutdown because: ctrl-c (SIGINT)",
                       "[INFO] [launch.user]: shutdown because: Window closed"], out


def test_a_session_stopped_by_sigint_says_ctrl_c(write, tmp_path):
    """The session server (a detached launch) gets SIGINT as ros2 launch would."""
    marker = tmp_path / "reason.txt"
    path = write(HEADER + f"""
def remember(event, context):
    with open({str(marker)!r}, 'w') as handle:
        handle.write(event.reason)
    return []

def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(cmd=['sleep', '60'], name='sleeper'),
        RegisterEventHandler(OnShutdown(on_shutdown=remember)),
    ])
""")
    runtime = tmp_path / "run"
    runtime.mkdir(mode=0o700)
    env = {**os.environ, "XDG_RUNTIME_DIR": str(runtime)}

    def tl(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "tuilaunch", *args], env=env,
                              capture_output=True, text=True, timeout=120)

    tl(str(path), "--detach", "--name", "words")
    try:
        tl("wait", "words", "sleeper-1", "running", "--timeout", "60")
        server = json.loads(tl("status", "words", "--json").stdout)["pid"]
        os.kill(server, signal.SIGINT)
        wait_for(lambda: marker.exists() and marker.read_text(), what="the OnShutdown handler")
    finally:
        tl("stop", "words")
    assert marker.read_text() == "ctrl-c (SIGINT)"


def test_an_xml_node_with_on_exit_shutdown_ends_the_launch_as_launch_does(write):
    path = write("""<launch>
  <executable cmd="sleep 60" name="sleeper"/>
  <executable cmd="true" name="required" on_exit="shutdown"/>
</launch>
""", "required.launch.xml")
    done = run_cli(str(path), "--headless")
    lines = done.stdout.splitlines()
    assert "[INFO] [launch]: process[required-2] was required: shutting down launched " \
        "system" in lines, done.stdout
    assert not [line for line in lines if "shutdown (" in line], done.stdout


# launch's own texts (launch/actions/shutdown_action.py, launch/launch_service.py,
# launch/actions/execute_local.py): the only lines it prints when a launch ends
REQUIRED = "[INFO] [launch]: process[{}] was required: shutting down launched system"
CTRL_C = "[WARNING] [launch]: user interrupted with ctrl-c (SIGINT)"
SIGINT_SENT = "[INFO] [sleeper-1]: sending signal 'SIGINT' to process[sleeper-1]"


@pytest.mark.parametrize("on_exit, elsewhere, required", [
    ("Shutdown()", "", True),
    ("Shutdown(reason='quick is done')", "", True),
    ("EmitEvent(event=ShutdownEvent())", "", False),
    ("EmitEvent(event=ShutdownEvent(reason='quick is done'))", "", False),
    # a TimerAction keeps the locals it was executed with (timer_action.py): the exit's event
    ("TimerAction(period=0.1, actions=[Shutdown(reason='later')])", "", True),
    ("LogInfo(msg='quick ended')", "TimerAction(period=0.5, actions=[Shutdown()]),", False),
])
def test_each_way_to_shut_down_prints_what_launch_prints(write, on_exit, elsewhere, required):
    """Only launch's Shutdown action, run by a process's exit, says `process[x] was
    required`; an emitted Shutdown event says nothing, nor a Shutdown a timer of the file
    runs (its locals hold no ProcessExited); no reason is printed, whatever it is."""
    path = write(HEADER + f"""
from launch.actions import TimerAction

def generate_launch_description():
    quick = ExecuteProcess(cmd=['true'], name='quick')
    return LaunchDescription([
        ExecuteProcess(cmd=['sleep', '60'], name='sleeper'),
        quick,
        RegisterEventHandler(OnProcessExit(target_action=quick, on_exit=[{on_exit}])),
        {elsewhere}
    ])
""")
    done = run_cli(str(path), "--headless")
    lines = done.stdout.splitlines()
    assert done.returncode == 0, done.stdout + done.stderr
    said = [line for line in lines if "[launch]" in line][2:]  # after the two first lines
    assert said == ([REQUIRED.format("quick-2")] if required else []), done.stdout
    assert SIGINT_SENT in lines, done.stdout  # not Ctrl+C: launch sends SIGINT and says so
    assert not [line for line in lines if "reason" in line or "quick is done" in line]


def test_ctrl_c_prints_what_launch_prints(write):
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(cmd=['sleep', '60'], name='sleeper')])
""")
    lines = run_headless(path, until=("process started",)).splitlines()
    said = [line for line in lines if "[launch]" in line][2:]
    # launch's warning, then tuilaunch's own line on Ctrl+C again (documented); the SIGINT
    # came from the terminal, so it is not announced; no reason line
    assert said == [CTRL_C, "[INFO] [launch]: stopping: Ctrl+C again sends SIGTERM now, a "
                    "third time SIGKILL"], lines
    assert SIGINT_SENT not in lines and not [line for line in lines if "shutdown (" in line]


def test_sigterm_says_what_ros2_launch_says_exits_1_and_leaves_nothing_running(write):
    """launch_service.py's _on_sigterm (SIGTERM and SIGQUIT) logs `user interrupted with
    ctrl-\\ (SIGTERM), terminating...` and cancels the run (exit status 1). tuilaunch says
    the same and exits 1, but stops every process first (its OnShutdown handlers run)."""
    for sig, marker in ((signal.SIGTERM, "sleep 64.5"), (signal.SIGQUIT, "sleep 65.5")):
        path = write(HEADER + f"""
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(cmd={marker.split()!r}, name='sleeper'),""" + ON_SHUTDOWN + """
    ])
""")
        proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                start_new_session=True)
        try:
            assert proc.stdout is not None
            seen = ""
            while "process started" not in seen:
                line = proc.stdout.readline()
                assert line, seen
                seen += line
            proc.send_signal(sig)
            seen += proc.communicate(timeout=60)[0]
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
        lines = seen.splitlines()
        assert (f"[ERROR] [launch]: user interrupted with ctrl-\\ ({sig.name}), terminating..."
                in lines), seen
        assert f"[INFO] [launch.user]: shutdown because: received {sig.name}" in lines, seen
        assert proc.returncode == 1, seen
        wait_for(lambda: not subprocess.run(["pgrep", "-f", marker],  # noqa: B023
                                            capture_output=True).stdout, what=marker)


def test_output_puts_on_screen_what_launch_s_output_loggers_do(write, tmp_path):
    """launch.logging.get_output_loggers: 'log' prints only stderr on the screen, 'own_log'
    nothing, a dict per stream; without `output` both are shown (tuilaunch's default).
    Every line is in the process's log file whatever is printed."""
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(cmd=['sh', '-c', 'echo log out; echo log err >&2'], name='log',
                       output='log'),
        ExecuteProcess(cmd=['sh', '-c', 'echo own out; echo own err >&2'], name='own',
                       output='own_log'),
        ExecuteProcess(cmd=['sh', '-c', 'echo dict out; echo dict err >&2'], name='dict',
                       output={'stdout': 'screen', 'stderr': ['log']}),
        ExecuteProcess(cmd=['sh', '-c', 'echo plain out; echo plain err >&2'], name='plain'),
    ])
""")
    logs = tmp_path / "logs"
    done = run_cli(str(path), "--headless", env={"ROS_LOG_DIR": str(logs)})
    assert done.returncode == 0, done.stdout + done.stderr
    printed = {line for line in done.stdout.splitlines() if not line.startswith("[INFO]")}
    assert printed == {"[log-1] log err", "[dict-3] dict out", "[plain-4] plain out",
                       "[plain-4] plain err"}, done.stdout
    folder = next(logs.glob("*-tuilaunch-*"))
    for name, number in (("log", 1), ("own", 2), ("dict", 3)):
        kept = (folder / f"{name}-{number}.log").read_text()
        assert f"{name} out" in kept and f"{name} err" in kept
    # ros2 launch's override for every process, as launch_testing and CI set it
    done = run_cli(str(path), "--headless", env={"ROS_LOG_DIR": str(logs),
                                                 "OVERRIDE_LAUNCH_PROCESS_OUTPUT": "screen"})
    printed = {line for line in done.stdout.splitlines() if not line.startswith("[INFO]")}
    assert len(printed) == 8, done.stdout
    # ros2 launch's -a (--show-all-subprocesses-output) sets that override to 'both'
    done = run_cli(str(path), "--headless", "-a", env={"ROS_LOG_DIR": str(logs)})
    printed = {line for line in done.stdout.splitlines() if not line.startswith("[INFO]")}
    assert len(printed) == 8, done.stdout


def test_an_output_launch_does_not_know_is_one_line_naming_where(write):
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(cmd=['true'], output='scren')])
""")
    done = run_cli(str(path), "--headless")
    assert done.returncode == 2
    line = next(n for n, text in enumerate(path.read_text().splitlines(), 1) if "scren" in text)
    assert done.stderr.strip().splitlines()[0].endswith(
        f"{path.name}:{line}: output 'scren' is not one of screen, log, both, own_log, full"), \
        done.stderr
    assert "Traceback" not in done.stderr
    done = run_cli(str(path), "--headless", env={"OVERRIDE_LAUNCH_PROCESS_OUTPUT": "loud"})
    assert done.returncode == 2
    assert done.stderr.strip() == "tuilaunch: error: OVERRIDE_LAUNCH_PROCESS_OUTPUT='loud' " \
        "is not one of screen, log, both, own_log, full", done.stderr


def test_log_cmd_and_output_format_print_as_launch_s_execute_local(write, tmp_path):
    """log_cmd=True says the final command before it starts ("process details: cmd='...',
    cwd='...', custom_env?=True": launch's env is always a dict now); output_format is
    `.format(line=..., this=the action)`."""
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(cmd=['echo', 'bare', ' '], name='raw', output='screen',
                       output_format='{line}', log_cmd=True, cwd='/tmp'),
        ExecuteProcess(cmd=['echo', 'named'], name='fancy', output='screen',
                       output_format='<{this.process_description.final_name}> {line}'),
    ])
""")
    done = run_cli(str(path), "--headless", env={"ROS_LOG_DIR": str(tmp_path / "logs")})
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    details = "[INFO] [raw-1]: process details: cmd='echo bare', cwd='/tmp', custom_env?=True"
    assert details in lines, done.stdout
    assert lines.index(details) < lines.index(next(line for line in lines
                                                   if "[raw-1]: process started" in line))
    assert "bare  " in lines and "<fancy-2> named" in lines, done.stdout


def test_a_log_info_of_the_file_is_said_before_any_process_starts(write):
    """launch performs a LogInfo while it visits the file; a process's `process started`
    comes once the loop runs: every such line first, whatever their order in the file."""
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(cmd=['true'], name='first'),
        LogInfo(msg='written after the first process'),
        ExecuteProcess(cmd=['true'], name='second'),
        LogInfo(msg='written last'),
    ])
""")
    done = run_cli(str(path), "--headless")
    lines = [line for line in done.stdout.splitlines() if "[launch]" not in line]
    assert lines[:4] == [
        "[INFO] [launch.user]: written after the first process",
        "[INFO] [launch.user]: written last",
        lines[2], lines[3]], done.stdout
    assert lines[2].startswith("[INFO] [first-1]: process started with pid [")
    assert lines[3].startswith("[INFO] [second-2]: process started with pid [")
