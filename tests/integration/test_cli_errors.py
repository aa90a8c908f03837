"""The command line: --show-args, --print, --json, PACKAGE FILE, and every bad input."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap

import pytest

from ..conftest import EXAMPLES, run_cli, run_headless, sl_file
from .launch_world import make_package

HEADER = "from simple_launch import SimpleLauncher\n"
BRINGUP = str(EXAMPLES / "bringup.py")


def test_show_args_lists_every_argument_with_default_description_and_choices():
    result = run_cli(BRINGUP, "--show-args")
    assert result.returncode == 0, result.stderr
    out = result.stdout
    for name in ("robot", "rate", "listener", "services", "mode", "topic"):
        assert f"'{name}':" in out
    assert "robot name, used as the namespace of its nodes" in out
    # ros2 launch's lines: the default quoted, the choices said in the description
    assert "\n        (default: 'r1')\n" in out
    assert "\n        mode given to the configurable node. Valid choices are: ['idle', " \
        "'patrol', 'dock']\n" in out
    assert "monitor.launch.py" in out  # an included file's argument says where it comes from


def test_print_tree_shows_groups_triggers_and_skipped_branches_with_reasons():
    result = run_cli(BRINGUP, "--print", "robot:=r2", "listener:=false")
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert "4 of 5 processes will run" in out
    assert "ns /r2" in out and "/r2/<talker>" in out
    assert "1 s after talker-1 starts" in out
    assert "(skipped) if $(var listener)  = 'false'" in out
    assert "listener-2 /r2/<listener>: if $(var listener) is 'false'" in out


def test_print_json_has_the_documented_fields():
    result = run_cli(BRINGUP, "--print", "--json", "robot:=r2", "mode:=dock")
    assert result.returncode == 0, result.stderr
    plan = json.loads(result.stdout)
    arg = next(a for a in plan["arguments"] if a["name"] == "mode")
    assert {k: arg[k] for k in ("default", "value", "choices")} == {
        "default": "patrol", "value": "dock", "choices": ["idle", "patrol", "dock"]}
    talker = plan["processes"][0]
    for key in ("id", "name", "namespace", "package", "executable", "cmd", "parameters",
                "parameter_files", "remappings", "enabled", "trigger"):
        assert key in talker
    assert talker["namespace"] == "/r2" and talker["parameters"]["message"] == "r2 says hi"
    configurable = next(p for p in plan["processes"] if p["executable"] == "configurable")
    assert configurable["trigger"] == {"on": "start", "target": talker["id"], "delay": 1.0}
    kinds = {(a["kind"], a["target"], json.dumps(a["data"])) for a in plan["actions"]}
    assert ("set_parameters", "/r2/control/configurable", '{"mode": "dock"}') in kinds
    assert ("call_service", "/r2/reset", "{}") in kinds


def test_package_and_file_like_ros2_launch():
    result = run_cli("tuilaunch_demos", "monitor.launch.py", "--print", "--json", "topic:=/t")
    assert result.returncode == 0, result.stderr
    (monitor,) = json.loads(result.stdout)["processes"]
    assert monitor["remappings"] == [["chatter", "/t"]]


def check_error(result, *fragments: str) -> None:
    assert result.returncode != 0
    assert "Traceback" not in result.stderr, result.stderr
    for fragment in fragments:
        assert fragment in result.stderr, result.stderr


def test_syntax_error_names_file_and_line(write):
    path = write(HEADER + "def generate_launch_description(:\n    pass\n")
    check_error(run_cli(str(path), "--print"), f"{path}:2", "syntax error")


def test_exception_in_launch_file_names_file_and_line(write):
    path = write(sl_file("""
    x = {}['missing']
"""))
    check_error(run_cli(str(path), "--print"), f"{path}:5", "KeyError")


def test_debug_shows_the_traceback(write):
    path = write(HEADER + "def generate_launch_description():\n    raise RuntimeError('boom')\n")
    result = run_cli(str(path), "--print", "--debug")
    assert result.returncode != 0 and "Traceback" in result.stderr and "boom" in result.stderr


def test_wrong_dsl_arguments(write):
    path = write(sl_file("""
    sl.node('tuilaunch_demos', 'talker', paramters={'a': 1})
"""))
    check_error(run_cli(str(path), "--print"), f"{path}:5", "unknown argument(s): paramters")


def test_unknown_package_and_executable(write):
    path = write(sl_file("""
    sl.node('no_such_pkg', 'x')
    sl.node('tuilaunch_demos', 'no_such_exe')
    sl.node('tuilaunch_demos', 'talker')
"""))
    result = run_cli(str(path), "--print", "--json")
    check_error(result, "package 'no_such_pkg' not found in the ament index",
                "executable 'no_such_exe' not found in package 'tuilaunch_demos'",
                "available: component_container, configurable, lifecycle_talker, listener, "
                "service_server, talker")
    plan = json.loads(result.stdout)  # the plan is still printed whole
    assert [p["error"] is None for p in plan["processes"]] == [False, False, True]


def test_unknown_launch_file_and_package_on_the_command_line(tmp_path):
    check_error(run_cli(str(tmp_path / "nope.py"), "--print"), "nope.py does not exist")
    check_error(run_cli("no_such_pkg", "x.launch.py", "--print"),
                "package 'no_such_pkg' not found")
    check_error(run_cli("tuilaunch_demos", "x.launch.py", "--print"),
                "launch file 'x.launch.py' not found in package 'tuilaunch_demos'")


def test_a_launch_file_name_found_twice_in_a_package_is_an_error_naming_both(tmp_path):
    # as ros2 launch: a built package whose share holds the source tree as well as the
    # installed launch folder has the file twice, and neither is silently chosen
    text = "<launch><log message='hi'/></launch>\n"
    make_package(tmp_path, "twice_pkg", files={"launch/a.launch.xml": text,
                                               "bringup/launch/a.launch.xml": text,
                                               "launch/b.launch.xml": text})
    env = {"AMENT_PREFIX_PATH": os.pathsep.join([str(tmp_path),
                                                 os.environ.get("AMENT_PREFIX_PATH", "")])}
    result = run_cli("twice_pkg", "a.launch.xml", "--print", env=env)
    check_error(result, "launch file 'a.launch.xml' is in package 'twice_pkg' more than once",
                "bringup/launch/a.launch.xml", "share/twice_pkg/launch/a.launch.xml")
    assert "log: hi" in run_cli("twice_pkg", "b.launch.xml", "--print", env=env).stdout


def test_value_outside_choices_and_non_boolean_condition():
    check_error(run_cli(BRINGUP, "--print", "mode:=fly"),
                "argument 'mode' = 'fly' is not one of its choices: idle, patrol, dock",
                "bringup.py:")
    check_error(run_cli(BRINGUP, "--print", "listener:=maybe"),
                "argument 'listener' = 'maybe'", "pass listener:=true or listener:=false")


def test_missing_generate_launch_description(write):
    path = write("x = 1\n")
    check_error(run_cli(str(path), "--print"), "defines no generate_launch_description()")


def test_a_file_that_exits_or_returns_nothing_says_so_at_its_line(write):
    path = write("import sys\nif True:\n    sys.exit(3)\n")
    check_error(run_cli(str(path), "--print"),
                f"{path}:3: the file called sys.exit(3) while loading")
    path = write("\n\ndef generate_launch_description():\n    return None\n")
    check_error(run_cli(str(path), "--print"),
                f"{path}:3: generate_launch_description() returned None")


@pytest.mark.parametrize("text", ["no_name_here", ":=value"])
def test_malformed_command_line_argument(text):
    check_error(run_cli(BRINGUP, text, "--print"))


@pytest.mark.parametrize("mode", ["--headless", "--print"])
def test_ctrl_c_while_the_file_loads_is_one_line_and_status_130(write, tmp_path, mode):
    """A slow file (xacro, a network lookup) interrupted before anything runs."""
    path = write("""
import sys, time
from launch import LaunchDescription
def generate_launch_description():
    print('loading', file=sys.stderr, flush=True)
    for _ in range(600):
        time.sleep(0.1)
    return LaunchDescription([])
""")
    # Steps, as a slow file's work is (xacro, a lookup): Python sees a signal between them.
    # One sleep(60) would not see a Ctrl+C that came between the print and the sleep until
    # it returned (the interpreter's race, not ours: 1 run in ~450 under load hung so).
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), mode],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "ROS_LOG_DIR": str(tmp_path)})
    try:
        assert proc.stderr is not None
        assert proc.stderr.readline() == "loading\n"
        proc.send_signal(signal.SIGINT)
        out, errors = proc.communicate(timeout=30)
        assert proc.returncode == 130 and out == ""
        assert errors == "tuilaunch: interrupted\n"
    finally:
        if proc.poll() is None:  # not interrupted: it does not outlive the test
            proc.kill()
            proc.wait()



def test_what_a_python_file_finds_but_is_not_installed_fails_only_its_process(write, tmp_path):
    """FindExecutable of a program that is not there (`ros2 bag record` on a robot without
    ros2cli) and FindPackageShare of a package that is not installed (an rviz config from
    nav2_bringup): ros2 launch stops everything; here those processes fail alone."""
    path = write("""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
from launch.substitutions import FindExecutable, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.substitutions import FindPackageShare
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(cmd=[FindExecutable(name='no-such-tool-tl'), 'record', '-a']),
        Node(package='tuilaunch_demos', executable='talker', name='viz', arguments=[
            '-d', PathJoinSubstitution([FindPackageShare('no_such_pkg_tl'), 'x.rviz'])]),
        ExecuteProcess(cmd=['sh', '-c', 'echo fine; sleep 600'], name='fine'),
    ])
""")
    printed = run_cli(str(path), "--print")
    assert printed.returncode == 3 and "Traceback" not in printed.stderr
    assert f"{path}:9: no-such-tool-tl-1" in printed.stderr
    assert "executable 'no-such-tool-tl' not found on PATH" in printed.stderr
    assert f"{path}:10: viz-2 (/viz): package 'no_such_pkg_tl' not found" in printed.stderr
    out = run_headless(path, until=("[fine-3] fine",), env={"ROS_LOG_DIR": str(tmp_path)})
    assert "[ERROR] [no-such-tool-tl-1]: failed to start: executable 'no-such-tool-tl' not " \
        "found on PATH" in out
    assert "[ERROR] [viz-2]: failed to start: package 'no_such_pkg_tl' not found" in out
    assert "[fine-3] fine" in out


def test_version_prints_the_installed_version_and_exits():
    from importlib import metadata

    result = run_cli("--version")
    assert result.returncode == 0, result.stderr
    assert result.stdout == f"tuilaunch {metadata.version('tuilaunch')}\n"
    # with a file too, as ros2 launch FILE --version would
    assert run_cli(BRINGUP, "--version").stdout == result.stdout


def one_error(result: subprocess.CompletedProcess[str]) -> str:
    assert result.returncode == 2, result.stdout
    assert "Traceback" not in result.stderr
    assert result.stderr.startswith("tuilaunch: error: "), result.stderr
    return result.stderr


def test_mistyped_files_and_packages_get_a_did_you_mean(tmp_path):
    near = str(EXAMPLES / "brinup.py")
    assert "hint: did you mean 'bringup.py'?" in one_error(run_cli(near, "--print"))
    prefix = tmp_path / "prefix"
    make_package(prefix, "fancy_robot", files={"launch/fancy.launch.py": "x = 1\n",
                                               "launch/sim_launch.xml": "<launch/>\n",
                                               "config/a.yaml": "{}\n"})
    env = {"AMENT_PREFIX_PATH": f"{prefix}{os.pathsep}{os.environ.get('AMENT_PREFIX_PATH', '')}"}
    wrong = one_error(run_cli("fancy_robto", "fancy.launch.py", "--print", env=env))
    assert "package 'fancy_robto' not found" in wrong and "did you mean 'fancy_robot'" in wrong
    # a package without a file: its launch files
    bare = one_error(run_cli("fancy_robot", "--print", env=env))
    assert "fancy_robot is a package: give one of its launch files too " \
        "(fancy.launch.py, sim_launch.xml)" in bare
    missing = one_error(run_cli("fancy_robot", "fancy_launch.py", "--print", env=env))
    assert "did you mean 'fancy.launch.py'?" in missing
    assert "its launch files: fancy.launch.py, sim_launch.xml" in missing


def test_a_missing_file_is_guessed_only_from_the_folder_it_names(tmp_path):
    """A file of the current folder is no guess for a package's name, nor for a file of
    another folder."""
    (tmp_path / "count.py").write_text("x = 1\n")
    (tmp_path / "sub").mkdir()

    def error(*args: str) -> str:
        done = subprocess.run([sys.executable, "-m", "tuilaunch", *args, "--print"],
                              capture_output=True, text=True, timeout=120, cwd=tmp_path)
        return one_error(done)

    assert "hint: did you mean 'count.py'?" in error("cont.py")  # this folder's file
    assert "count.py" not in error("cont")  # a word: a package, not this folder's file
    assert "count.py" not in error("sub/cont.py")  # sub holds no count.py
    assert "count.py" not in error("tuilaunch_demo")
    assert "did you mean the package 'tuilaunch_demos'?" in error("tuilaunch_demo")
    # a session command mistyped: the command, not a file
    assert "hint: did you mean the command 'ls'? (tuilaunch ls ...)" in error("list")
    assert "did you mean the command" not in error("lst.py")
    assert "hint: did you mean the command 'attach'?" in error("atach", "base")


def test_an_argument_without_its_colon_and_a_file_that_is_no_launch_file(tmp_path):
    error = one_error(run_cli(BRINGUP, "robot=r2", "--print"))
    assert "'robot=r2' is not a launch argument: ros2 launch arguments are written with " \
        "':='" in error and "hint: robot:=r2" in error
    notes = tmp_path / "notes.txt"
    notes.write_text("remember the milk\n")
    error = one_error(run_cli(str(notes), "--print"))
    assert f"{notes} is not a launch file" in error


def test_print_counts_only_the_processes_that_can_start(write):
    path = write("from launch.actions import ExecuteProcess\n" + HEADER + textwrap.dedent("""\
        sl = SimpleLauncher()
        sl.node('no_such_package_x', 'talker')
        sl.node('no_such_package_y', 'listener')
        sl.add_action(ExecuteProcess(cmd=['true'], name='fine'))
        def generate_launch_description():
            return sl.launch_description()
        """))
    result = run_cli(str(path), "--print")
    assert result.returncode == 3
    assert result.stdout.splitlines()[0].endswith(
        ": 1 of 3 processes will run (2 cannot start: !!)")


def test_a_value_unlike_the_defaults_type_is_taken_as_ros2_launch_takes_it(tmp_path):
    # launch arguments are strings: simple_launch's own examples pass robot2_x:=3.5 for a
    # default of 0, and ros2 launch passes it on as written
    path = tmp_path / "pose.launch.py"
    path.write_text(HEADER + textwrap.dedent("""\
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            sl = SimpleLauncher()
            sl.declare_arg('x', default_value=1)
            sl.declare_arg('rate', default_value=2.0)
            sl.add_action(ExecuteProcess(cmd=['echo', 'x is', sl.arg('x'), sl.arg('rate')],
                                         name='say', output='screen'))
            return sl.launch_description()
        """))
    printed = run_cli(str(path), "x:=3.5", "rate:=fast", "--print", "--json")
    assert printed.returncode == 0, printed.stderr
    assert json.loads(printed.stdout)["processes"][0]["cmd"][-2:] == ["3.5", "fast"]
    shown = run_cli(str(path), "x:=3.5", "--show-args")
    assert shown.returncode == 0, shown.stderr
    assert "'x':" in shown.stdout and "(default: '1')" in shown.stdout
    out = run_headless(path, "x:=3.5", "rate:=fast", until=("x is 3.5 fast",))
    assert "x is 3.5 fast" in out
    # a value outside an argument's choices is still refused, as DeclareLaunchArgument does
    refused = run_cli(BRINGUP, "mode:=fly", "--print")
    assert refused.returncode == 2 and "Traceback" not in refused.stderr
    assert "'fly'" in refused.stderr and "choices" in refused.stderr


def test_an_argument_an_include_overrides_is_said(tmp_path):
    (tmp_path / "child.launch.py").write_text(textwrap.dedent("""\
        from launch import LaunchDescription
        from launch.actions import DeclareLaunchArgument, ExecuteProcess
        from launch.substitutions import LaunchConfiguration


        def generate_launch_description():
            return LaunchDescription([
                DeclareLaunchArgument('rate', default_value='1.0'),
                ExecuteProcess(cmd=['echo', LaunchConfiguration('rate')], name='child'),
            ])
        """))
    parent = tmp_path / "parent.launch.py"
    parent.write_text(textwrap.dedent("""\
        import os
        from launch import LaunchDescription
        from launch.actions import DeclareLaunchArgument, IncludeLaunchDescription
        from launch.launch_description_sources import PythonLaunchDescriptionSource


        def generate_launch_description():
            return LaunchDescription([
                DeclareLaunchArgument('rate', default_value='2.0'),
                IncludeLaunchDescription(
                    PythonLaunchDescriptionSource(
                        os.path.join(os.path.dirname(__file__), 'child.launch.py')),
                    launch_arguments={'rate': '5.0'}.items()),
            ])
        """))
    said = run_cli(str(parent), "rate:=3", "--print")
    assert said.returncode == 0, said.stderr
    assert f"{parent}:10: the include of child.launch.py passes rate:=5.0, which overrides " \
        "rate:=3 from the command line in that file" in said.stdout + said.stderr
    # the same value, or none given: nothing to say
    assert "overrides" not in run_cli(str(parent), "rate:=5.0", "--print").stdout
    assert "overrides" not in run_cli(str(parent), "--print").stdout


TYPED = sl_file("""
    sl.declare_arg('gain', 1.5)
    sl.declare_arg('count', 3)
    sl.add_action(ExecuteProcess(name='uses', cmd=['sh', '-c', 'echo gain "$0"; exec sleep 600',
                                                   sl.arg('gain')]))
""", header=HEADER + "from launch.actions import ExecuteProcess\n")
GAIN_NOTE = "argument 'gain' = 'abc' is not a number like its default 1.5 (passed as written)"


def test_a_value_unlike_its_defaults_type_is_warned_headless_and_in_print(write):
    path = write(TYPED.replace("exec sleep 600", "true"))
    printed = run_cli(str(path), "gain:=abc", "count:=2.5", "--print")
    assert printed.returncode == 0, printed.stderr
    assert f"warning: {GAIN_NOTE}\n" in printed.stdout
    assert "argument 'count' = '2.5' is not a whole number like its default 3" in \
        printed.stdout
    ran = run_cli(str(path), "gain:=abc", "--headless")
    assert ran.returncode == 0, ran.stderr
    assert f"tuilaunch: warning: {GAIN_NOTE}\n" in ran.stderr
    assert "[uses-1] gain abc" in ran.stdout  # passed as written, as ros2 launch does
    fine = run_cli(str(path), "gain:=2", "count:=4", "--print")  # a whole number is a number
    assert "warning" not in fine.stdout + fine.stderr
