"""XML and YAML launch files run headless with real processes, and edit like Python ones."""

from __future__ import annotations

import json
import os
import signal
import sys
from pathlib import Path

import pytest

from tuilaunch.engine.plan.session import Session

from ..conftest import EXAMPLES, plan_of
from .test_supervisor import kill_leftovers, pids_of, read_until, start_headless, wait_gone

LAUNCH = EXAMPLES / "launch"
__all__ = ["kill_leftovers"]  # a fixture shared with the supervisor tests

# Stand-ins for the C++ executables of ros2_control and robot_state_publisher, which are not
# installable here: each prints what it was given, as the real one would read it.
FAKE_NODE = """#!{python}
import json, signal, sys, time, yaml
signal.signal(signal.SIGINT, lambda *_: sys.exit(0))
args = sys.argv[1:]
files = [args[i + 1] for i, a in enumerate(args) if a == '--params-file']
params = {{}}
for path in files:
    for node, body in yaml.safe_load(open(path)).items():
        params[node] = sorted((body or {{}}).get('ros__parameters', {{}}))
description = ''
for path in files:
    for body in yaml.safe_load(open(path)).values():
        found = (body or {{}}).get('ros__parameters', {{}})
        description = found.get('robot_description', description)
print('FAKE {name}', json.dumps({{'args': args[:args.index('--ros-args')] if '--ros-args' in args
      else args, 'params': params, 'links': description.count('<link ')}}), flush=True)
if {stays}:
    while True:
        time.sleep(1)
"""


@pytest.fixture
def control_prefix(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """An ament prefix with fake controller_manager and robot_state_publisher packages."""
    prefix = tmp_path / "fake_prefix"
    for package, executables in (("controller_manager", {"ros2_control_node": True,
                                                         "spawner": False}),
                                 ("robot_state_publisher", {"robot_state_publisher": True})):
        index = prefix / "share/ament_index/resource_index/packages"
        index.mkdir(parents=True, exist_ok=True)
        (index / package).write_text("")
        (prefix / "share" / package).mkdir(parents=True)
        (prefix / "share" / package / "package.xml").write_text(f"<package><name>{package}"
                                                                 "</name></package>")
        (prefix / "lib" / package).mkdir(parents=True)
        for exe, stays in executables.items():
            script = prefix / "lib" / package / exe
            script.write_text(FAKE_NODE.format(python=sys.executable, name=exe, stays=stays))
            script.chmod(0o755)
    monkeypatch.setenv("AMENT_PREFIX_PATH",
                       str(prefix) + os.pathsep + os.environ.get("AMENT_PREFIX_PATH", ""))
    return prefix


def test_ros2_control_bringup_resolves_like_ros2_launch(control_prefix):
    plan = plan_of(LAUNCH / "robot_control.launch.xml", prefix="r2/")
    manager, publisher, rviz, broadcaster, forward = plan.processes
    controllers = str(LAUNCH / "robot_controllers.yaml")
    assert (manager.package, manager.executable, manager.name) == (
        "controller_manager", "ros2_control_node", None)
    assert manager.parameter_files == [controllers] and manager.parameters == {}
    assert manager.remappings == [["~/robot_description", "/robot_description"]]
    description = publisher.parameters["robot_description"]
    assert isinstance(description, str) and '<link name="r2/base_link"/>' in description
    assert not rviz.enabled and rviz.full_name == "/rviz2"
    assert broadcaster.cmd[1:] == ["joint_state_broadcaster", "--ros-args"]
    assert forward.cmd[1:] == ["forward_position_controller", "--param-file", controllers,
                               "--controller-ros-args", "-r ~/commands:=/commands",
                               "--ros-args"]
    assert all(p.error is None for p in plan.processes if p.enabled)
    assert plan_of(LAUNCH / "robot_control.launch.xml", gui="true").processes[2].enabled


def test_ros2_control_bringup_runs_headless(control_prefix, tmp_path, kill_leftovers):
    proc = start_headless(str(LAUNCH / "robot_control.launch.xml"), log_dir=tmp_path / "logs")
    kill_leftovers.append(proc)
    seen = read_until(proc, "FAKE ros2_control_node", "FAKE robot_state_publisher",
                      "[spawner-4] FAKE spawner", "[spawner-5] FAKE spawner",
                      "[INFO] [spawner-4]: process has finished",
                      "[INFO] [spawner-5]: process has finished")
    reports = {line.split("] ", 1)[0] + "]": json.loads(line.split("FAKE ", 1)[1].split(" ", 1)[1])
               for line in seen.splitlines() if "FAKE " in line}
    assert reports["[ros2_control_node-1]"]["params"]["controller_manager"] == [
        "forward_position_controller", "joint_state_broadcaster", "update_rate"]
    assert reports["[robot_state_publisher-2]"]["links"] == 2
    assert reports["[spawner-4]"]["args"] == ["joint_state_broadcaster"]
    assert reports["[spawner-5]"]["args"][:2] == ["forward_position_controller", "--param-file"]
    os.killpg(proc.pid, signal.SIGINT)
    rest = proc.communicate(timeout=60)[0]
    assert proc.returncode == 0, rest
    assert wait_gone(pids_of(tmp_path / "logs")) == []


def test_xml_bringup_runs_real_nodes_with_names_namespaces_and_parameters(tmp_path,
                                                                          kill_leftovers):
    proc = start_headless(str(LAUNCH / "bringup.launch.xml"), "robot:=r6", "rate:=20",
                          log_dir=tmp_path)
    kill_leftovers.append(proc)
    seen = read_until(proc, '[talker-1] STARTUP {"node": "/r6/talker"',
                      'I heard: "r6 says hi', '[monitor-4] STARTUP {"node": "/r6/monitor"',
                      '"chatter": "/r6/chatter"', '[configurable-3] STARTUP {"node": '
                      '"/r6/control/configurable"')
    assert '"rate": 20' in seen and '"message": "r6 says hi"' in seen
    os.killpg(proc.pid, signal.SIGINT)
    proc.communicate(timeout=60)
    assert wait_gone(pids_of(tmp_path)) == []


def test_yaml_talker_listener_runs_headless(tmp_path, kill_leftovers):
    proc = start_headless(str(LAUNCH / "talker_listener.launch.yaml"), log_dir=tmp_path)
    kill_leftovers.append(proc)
    read_until(proc, "[talker-1] STARTUP", "[listener-2]", "I heard")
    os.killpg(proc.pid, signal.SIGINT)
    proc.communicate(timeout=60)
    assert wait_gone(pids_of(tmp_path)) == []


def test_argument_edits_preview_and_restart_only_what_changes(tmp_path):
    session = Session(str(LAUNCH / "bringup.launch.xml"), {}, params_dir=tmp_path)
    preview = session.preview({"mode": "dock"})
    assert preview.error is None and preview.diff is not None
    assert preview.diff.stop == ["configurable-3"] == preview.diff.start
    assert set(preview.diff.keep) == {"talker-1", "listener-2", "monitor-4"}
    bad = session.preview({"mode": "fly"})
    assert bad.error is not None and "bringup.launch.xml:9" in bad.error
    swap = session.preview({"listener": "false"})
    assert swap.diff is not None
    assert "listener-2" in swap.diff.stop and {"talker-5", "listener-6"} <= set(swap.diff.start)
    session.accept(swap)
    assert [p.id for p in session.plan.enabled_processes()] == [
        "talker-1", "configurable-3", "monitor-4", "talker-5", "listener-6"]


def test_package_and_xml_file_like_ros2_launch(control_prefix):
    from ..conftest import run_cli

    launch_dir = control_prefix / "share" / "controller_manager" / "launch"
    launch_dir.mkdir()
    (launch_dir / "manager.launch.xml").write_text(
        '<launch><node pkg="controller_manager" exec="ros2_control_node" name="cm"/></launch>')
    done = run_cli("controller_manager", "manager.launch.xml", "--print")
    assert done.returncode == 0, done.stderr
    assert "/cm  [cm-1] (controller_manager/ros2_control_node)" in done.stdout
