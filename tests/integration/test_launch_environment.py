"""Environment actions are what `os.environ` shows to Python run at launch time, as in launch.

In launch, `context.environment` is the launch process's `os.environ`
(launch/launch_context.py): SetEnvironmentVariable, AppendEnvironmentVariable,
UnsetEnvironmentVariable, Push/PopEnvironment (and so a scoped GroupAction) and
ResetEnvironment change it in the order they are visited, and OpaqueFunctions, included
files' module code, PythonExpression, conditions and EnvironmentVariable read the change.
The expected lines below follow from that; the launcher's own environment comes back after.
"""

from __future__ import annotations

import json
import os

from ..conftest import plan_of, run_cli

HEADER = """
import os
from launch import LaunchDescription
from launch.actions import (AppendEnvironmentVariable, ExecuteProcess, GroupAction,
                            IncludeLaunchDescription, LogInfo, OpaqueFunction, PopEnvironment,
                            PushEnvironment, RegisterEventHandler, ResetEnvironment,
                            SetEnvironmentVariable, UnsetEnvironmentVariable)
from launch.conditions import IfCondition
from launch.event_handlers import OnProcessExit
from launch.substitutions import EnvironmentVariable, PythonExpression
"""

# the pattern of ros_gz_sim's gz_sim.launch.py: the simulator's GZ_SIM_RESOURCE_PATH is
# built from os.environ in an OpaqueFunction and given as additional_env
GZ_SIM = HEADER + """
print('gz_sim module code sees', os.environ.get('GZ_SIM_RESOURCE_PATH'), flush=True)

def launch_gz(context, *args, **kwargs):
    paths = os.environ.get('GZ_SIM_RESOURCE_PATH', '')
    return [ExecuteProcess(cmd=['sh', '-c', 'echo simulator models: $GZ_SIM_RESOURCE_PATH'],
                           name='gz_sim', output='screen',
                           additional_env={'GZ_SIM_RESOURCE_PATH': paths + ':/gz/share'})]

def generate_launch_description():
    print('gz_sim generate sees', os.environ.get('GZ_SIM_RESOURCE_PATH'), flush=True)
    return LaunchDescription([OpaqueFunction(function=launch_gz)])
"""

BRINGUP = HEADER + """
def report(context, what):
    print(what, os.environ.get('GZ_SIM_RESOURCE_PATH'), os.environ.get('MARK'), flush=True)
    return []

def generate_launch_description():
    here = os.path.dirname(__file__)
    return LaunchDescription([
        SetEnvironmentVariable('MARK', 'one'),
        OpaqueFunction(function=report, args=['first opaque']),
        AppendEnvironmentVariable('GZ_SIM_RESOURCE_PATH', '/robot/models'),
        AppendEnvironmentVariable('GZ_SIM_RESOURCE_PATH', '/robot/first', prepend=True),
        IncludeLaunchDescription(os.path.join(here, 'gz_sim.launch.py')),
        SetEnvironmentVariable('MARK', 'two'),
        OpaqueFunction(function=report, args=['second opaque']),
        GroupAction([SetEnvironmentVariable('SCOPED', 'inside'),
                     LogInfo(msg=['in the group: ', EnvironmentVariable('SCOPED')])]),
        LogInfo(msg=['after the group: ',
                     EnvironmentVariable('SCOPED', default_value='unset')]),
        LogInfo(msg=PythonExpression(["'expression: ' + os.environ['MARK']"],
                                     python_modules=['os'])),
        LogInfo(msg='condition held', condition=IfCondition(
            PythonExpression(["os.environ['MARK'] == 'two'"], python_modules=['os']))),
        ExecuteProcess(cmd=['sh', '-c', 'echo child: $MARK'], name='child', output='screen'),
    ])
"""


def test_a_gz_sim_style_include_sees_what_was_appended_before_it(write, tmp_path):
    write(GZ_SIM, "gz_sim.launch.py")
    path = write(BRINGUP, "bringup.launch.py")
    done = run_cli(str(path), "--headless",
                   env={"GZ_SIM_RESOURCE_PATH": "/user/models", "MARK": "start"})
    out = done.stdout.splitlines()
    assert done.returncode == 0, done.stdout + done.stderr
    expected = "/robot/first:/user/models:/robot/models"
    # in launch's order of visiting: each line sees what came before it, nothing after
    assert out.index("first opaque /user/models one") \
        < out.index(f"gz_sim module code sees {expected}") \
        < out.index(f"gz_sim generate sees {expected}") \
        < out.index(f"second opaque {expected} two"), out
    assert f"[gz_sim-1] simulator models: {expected}:/gz/share" in out
    assert any(line.endswith("in the group: inside") for line in out), out
    assert any(line.endswith("after the group: unset") for line in out), out
    assert any(line.endswith("expression: two") for line in out), out
    assert any(line.endswith("condition held") for line in out), out
    # what children get is unchanged: the actions in scope on top of tuilaunch's environment
    assert "[child-2] child: two" in out


def test_scopes_push_pop_reset_and_unset_change_what_code_sees(write, monkeypatch, capsys):
    monkeypatch.setenv("KEPT", "from the shell")
    path = write(HEADER + """
def show(context, what):
    print(what, os.environ.get('KEPT'), os.environ.get('A'), flush=True)
    return []

def generate_launch_description():
    return LaunchDescription([
        SetEnvironmentVariable('A', 'a'),
        GroupAction([SetEnvironmentVariable('A', 'scoped')]),
        OpaqueFunction(function=show, args=['after scoped']),
        GroupAction([SetEnvironmentVariable('A', 'unscoped')], scoped=False),
        OpaqueFunction(function=show, args=['after unscoped']),
        GroupAction([OpaqueFunction(function=show, args=['not forwarded'])],
                    forwarding=False),
        PushEnvironment(),
        UnsetEnvironmentVariable('KEPT'),
        OpaqueFunction(function=show, args=['unset']),
        PopEnvironment(),
        OpaqueFunction(function=show, args=['popped']),
        ResetEnvironment(),
        OpaqueFunction(function=show, args=['reset']),
        AppendEnvironmentVariable('A', 'x', separator=';'),
        OpaqueFunction(function=show, args=['appended']),
        SetEnvironmentVariable('A', ''),
        AppendEnvironmentVariable('A', 'y'),  # set, even empty: launch adds the separator
        OpaqueFunction(function=show, args=['appended to empty']),
    ])
""")
    before = dict(os.environ)
    plan_of(path)
    printed = capsys.readouterr().out.splitlines()
    assert printed == [
        "after scoped from the shell a",
        "after unscoped from the shell unscoped",
        # forwarding=False: launch resets the environment to where the launch started
        "not forwarded from the shell None",
        "unset None unscoped",
        "popped from the shell unscoped",
        "reset from the shell None",
        "appended from the shell x",
        "appended to empty from the shell :y",
    ]
    assert dict(os.environ) == before  # the launcher's own environment is back


def test_a_relaunch_starts_from_the_environment_tuilaunch_started_with(write, monkeypatch,
                                                                      capsys):
    monkeypatch.setenv("TL_PATHS", "/base")
    path = write(HEADER + """
import os
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration

# module code that extends the environment, as some bringups do
os.environ['TL_PATHS'] = os.environ['TL_PATHS'] + ':/module'

def show(context):
    print('sees', os.environ['TL_PATHS'], flush=True)
    return []

def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('extra', default_value='/a'),
        AppendEnvironmentVariable('TL_PATHS', LaunchConfiguration('extra')),
        OpaqueFunction(function=show),
        ExecuteProcess(cmd=['true']),
    ])
""")
    from tuilaunch.engine.plan.session import Session

    session = Session(str(path), {})
    assert os.environ["TL_PATHS"] == "/base"
    preview = session.preview({"extra": "/b"})
    assert preview.plan is not None
    session.accept(preview)
    session.reload()
    assert os.environ["TL_PATHS"] == "/base"
    assert capsys.readouterr().out.splitlines() == [
        "sees /base:/module:/a", "sees /base:/module:/b", "sees /base:/module:/b"]
    # the module's own write reaches the child, as launch's os.environ would
    assert session.plan.processes[0].env["TL_PATHS"] == "/base:/module:/b"


def test_xml_environment_tags_are_seen_by_an_included_python_file(write, tmp_path):
    write(HEADER + """
print('python include sees', os.environ.get('TL_XML'), flush=True)

def generate_launch_description():
    return LaunchDescription([LogInfo(msg=EnvironmentVariable('TL_XML'))])
""", "inner.launch.py")
    path = write("""<launch>
  <set_env name="TL_XML" value="set"/>
  <append_env name="TL_XML" value="more" prepend="true" separator=","/>
  <log message="eval: $(eval 'os.environ[&quot;TL_XML&quot;]' os)"/>
  <include file="$(dirname)/inner.launch.py"/>
  <executable cmd="sh -c 'echo xml child: $TL_XML'" name="xmlchild" output="screen"/>
</launch>
""", "outer.launch.xml")
    done = run_cli(str(path), "--headless")
    out = done.stdout.splitlines()
    assert done.returncode == 0, done.stdout + done.stderr
    assert "python include sees more,set" in out
    assert any(line.endswith("eval: more,set") for line in out), out
    assert any(line.endswith("]: more,set") for line in out), out
    assert "[xmlchild-1] xml child: more,set" in out


def test_code_run_when_an_event_happens_sees_its_scope(write):
    path = write(HEADER + """
def after(context):
    return [LogInfo(msg='handler sees ' + os.environ.get('TL_EVENT', 'nothing'))]

def generate_launch_description():
    first = ExecuteProcess(cmd=['true'], name='first')
    return LaunchDescription([
        SetEnvironmentVariable('TL_EVENT', 'set'),
        first,
        RegisterEventHandler(OnProcessExit(target_action=first,
                                           on_exit=[OpaqueFunction(function=after)])),
    ])
""")
    done = run_cli(str(path), "--headless")
    assert any(line.endswith("handler sees set") for line in done.stdout.splitlines()), \
        done.stdout + done.stderr


def test_code_run_when_an_event_happens_sees_the_launch_environment_after_the_visit(write):
    """launch visits the whole description before any event is handled; a scoped group
    pushed and popped the environment by then (GroupAction's PushEnvironment/
    PopEnvironment), and a variable set later in the file is already there. Event-time
    code reads os.environ at that moment; what it writes stays for what follows."""
    path = write(HEADER + """
def opaque(context):
    print('opaque sees', os.environ.get('TL_SCOPED', 'no scoped'),
          os.environ.get('TL_LATE', 'no late'), flush=True)
    os.environ['TL_WRITTEN'] = 'by the opaque function'
    return []

def callback(event, context):
    print('callback sees', os.environ.get('TL_SCOPED', 'no scoped'),
          os.environ.get('TL_LATE', 'no late'), flush=True)
    return []

def generate_launch_description():
    first = ExecuteProcess(cmd=['true'], name='first')
    second = ExecuteProcess(cmd=['sh', '-c', 'echo second: ${TL_SCOPED-no scoped}'],
                            name='second', output='screen')
    return LaunchDescription([
        GroupAction([
            SetEnvironmentVariable('TL_SCOPED', 'inside'),
            first,
            RegisterEventHandler(OnProcessExit(target_action=first, on_exit=[
                OpaqueFunction(function=opaque),
                LogInfo(msg=['message sees ',
                             EnvironmentVariable('TL_SCOPED', default_value='no scoped')]),
                second,
            ])),
        ]),
        RegisterEventHandler(OnProcessExit(target_action=second, on_exit=callback)),
        SetEnvironmentVariable('TL_LATE', 'late'),
    ])
""")
    done = run_cli(str(path), "--headless")
    out = done.stdout.splitlines()
    assert done.returncode == 0, done.stdout + done.stderr
    assert "opaque sees no scoped late" in out, out
    assert any(line.endswith("message sees no scoped") for line in out), out
    assert out.count("callback sees no scoped late") == 1, out


def test_print_json_shows_each_process_environment_change(write):
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        SetEnvironmentVariable('TL_JSON', 'yes'),
        ExecuteProcess(cmd=['true'], name='one'),
    ])
""")
    done = run_cli(str(path), "--print", "--json")
    data = json.loads(done.stdout)
    assert data["processes"][0]["env"]["TL_JSON"] == "yes"


def test_print_json_says_what_tuilaunch_changes_in_every_environment_on_purpose(write):
    """Started without its virtual environment on PATH, tuilaunch puts its bin/ first (for
    scripts that start with `/usr/bin/env python3`): --print --json says so, and why."""
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(cmd=['true'], name='one')])
""")
    import sys

    venv_bin = os.path.dirname(sys.executable)
    done = run_cli(str(path), "--print", "--json", env={"PATH": "/usr/bin:/bin"})
    changes = json.loads(done.stdout)["environment_changes"]
    if os.path.isdir(os.path.join(sys.prefix, "share", "ament_index")):
        assert changes["PATH"]["before"] == "/usr/bin:/bin"
        assert changes["PATH"]["after"] == f"{venv_bin}:/usr/bin:/bin"
        assert "python3" in changes["PATH"]["why"]
    else:  # not an ament prefix: nothing is changed
        assert "PATH" not in changes


UNSET = HEADER + """
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(cmd=['sh', '-c', 'echo before: ${TL_GONE-absent}'], name='before'),
        GroupAction([
            UnsetEnvironmentVariable('TL_GONE'),
            ExecuteProcess(cmd=['sh', '-c', 'echo inside: ${TL_GONE-absent}'], name='inside'),
            ExecuteProcess(cmd=['sh', '-c', 'echo again: ${TL_GONE-absent}'], name='again',
                           additional_env={'TL_GONE': 'given'}),
        ]),
        ExecuteProcess(cmd=['sh', '-c', 'echo after: ${TL_GONE-absent}'], name='after'),
    ])
"""


def test_a_process_after_an_unset_does_not_inherit_the_variable(write):
    """launch's ExecuteLocal starts a child from context.environment (os.environ after the
    unset), so the process in the unset's scope lacks it; its additional_env may set it
    again; a process outside the scope keeps it."""
    path = write(UNSET)
    done = run_cli(str(path), "--headless", env={"TL_GONE": "inherited"})
    out = done.stdout.splitlines()
    assert done.returncode == 0, done.stdout + done.stderr
    assert "[before-1] before: inherited" in out, out
    assert "[inside-2] inside: absent" in out, out
    assert "[again-3] again: given" in out, out
    assert "[after-4] after: inherited" in out, out


def test_print_json_and_status_show_the_unset_variable(write, tmp_path):
    path = write(UNSET)
    done = run_cli(str(path), "--print", "--json", env={"TL_GONE": "inherited"})
    processes = {p["name"]: p for p in json.loads(done.stdout)["processes"]}
    assert processes["inside"]["unset_env"] == ["TL_GONE"]
    assert processes["again"]["unset_env"] == [] and processes["again"]["env"] == {
        "TL_GONE": "given"}
    assert processes["before"]["unset_env"] == []

    sleeper = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        UnsetEnvironmentVariable('TL_GONE'),
        ExecuteProcess(cmd=['sleep', '60'], name='sleeper'),
    ])
""", "sleeper.launch.py")
    runtime = tmp_path / "run"
    runtime.mkdir(mode=0o700)
    env = {"XDG_RUNTIME_DIR": str(runtime), "TL_GONE": "inherited"}
    run_cli(str(sleeper), "--detach", "--name", "unset", env=env)
    try:
        run_cli("wait", "unset", "sleeper-1", "running", "--timeout", "60", env=env)
        status = json.loads(run_cli("status", "unset", "--json", env=env).stdout)
        pid = next(p["pid"] for p in status["processes"] if p["id"] == "sleeper-1")
        with open(f"/proc/{pid}/environ", "rb") as handle:
            names = [item.split(b"=", 1)[0] for item in handle.read().split(b"\0")]
        assert b"TL_GONE" not in names
    finally:
        run_cli("stop", "unset", env=env)
    proc = next(p for p in status["processes"] if p["id"] == "sleeper-1")
    assert proc["unset_env"] == ["TL_GONE"], proc
    assert proc["command_line"].startswith("env -u TL_GONE -- "), proc["command_line"]
