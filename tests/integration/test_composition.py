"""Composable nodes: load requests as launch_ros builds them, loaded into a real container.

composition_interfaces has no wheel: the session fixture builds its Python bindings from the
.srv files in tests/integration/interfaces with the rosidl generators from PyPI (once per
definition, in
~/.cache/tuilaunch-tests). The container is the demo package's rclpy `component_container`,
which serves the same `_container/load_node` service as rclcpp_components.
"""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import sys
from pathlib import Path

import pytest

from tuilaunch.engine import load_file, resolve
from tuilaunch.engine.launcher import make_supervisor
from tuilaunch.engine.run.supervisor.supervisor import Event

from ..conftest import plan_of, run_cli, run_headless
from .interfaces.build_interfaces import build, default_cache

HEADER = """\
from launch import LaunchDescription
from launch.actions import GroupAction, DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import (ComposableNodeContainer, LoadComposableNodes, Node,
                                PushRosNamespace, SetParameter, SetRemap)
from launch_ros.descriptions import ComposableNode
"""


@pytest.fixture(scope="session")
def composition_interfaces() -> str:
    """The folder holding the built package; also on sys.path and every child's PYTHONPATH."""
    cache = default_cache()
    cache.mkdir(parents=True, exist_ok=True)
    folder = str(build(cache))
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return folder


def with_interfaces(folder: str) -> dict[str, str]:
    return {"PYTHONPATH": os.pathsep.join(p for p in (folder, os.environ.get("PYTHONPATH"))
                                          if p)}




CONTAINER = HEADER + """
def generate_launch_description():
    container = ComposableNodeContainer(
        name='box', namespace='', package='tuilaunch_demos', executable='component_container',
        respawn=True, respawn_delay=0.2,
        composable_node_descriptions=[
            ComposableNode(package='tuilaunch_demos', plugin='tuilaunch_demos::Talker',
                           name='talker_c', parameters=[{'message': 'from a component',
                                                         'rate': 20.0}],
                           remappings=[('chatter', '/shared/talk')],
                           extra_arguments=[{'use_intra_process_comms': True}]),
            ComposableNode(package='tuilaunch_demos', plugin='tuilaunch_demos::Nothing',
                           name='broken'),
        ])
    late = LoadComposableNodes(target_container=container, composable_node_descriptions=[
        ComposableNode(package='tuilaunch_demos', plugin='tuilaunch_demos::Listener',
                       name='listener_c', remappings=[('chatter', '/shared/talk')])])
    return LaunchDescription([container, late])
"""


# --- plans -------------------------------------------------------------------------------


def test_requests_follow_launch_ros_namespaces_parameters_and_remaps(write, tmp_path):
    params = tmp_path / "params.yaml"
    params.write_text("/**:\n  ros__parameters:\n    everyone: 1\n"
                      "robot/cam:\n  ros__parameters:\n    fps: 30\n    nested: {a: 2}\n"
                      "other:\n  ros__parameters:\n    fps: 99\n")
    plan = plan_of(write(HEADER + f"""
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('fps', default_value='15'),
        GroupAction([
            PushRosNamespace('robot'),
            SetParameter(name='use_sim_time', value=True),
            SetRemap(src='image', dst='image_raw'),
            ComposableNodeContainer(
                name='box', namespace='containers', package='tuilaunch_demos',
                executable='component_container',
                composable_node_descriptions=[
                    ComposableNode(package='cams', plugin='cams::Camera', name='cam',
                                   parameters=['{params}', {{'fps': LaunchConfiguration('fps')}}],
                                   remappings=[('info', 'camera_info')],
                                   extra_arguments=[{{'use_intra_process_comms': True}}]),
                    ComposableNode(package='cams', plugin='cams::Filter', namespace='/abs'),
                ]),
        ]),
    ])
"""))
    (container,) = plan.processes
    assert container.full_name == "/robot/containers/box"
    cam, filt = container.components
    # the pushed namespace, not the container's own: as launch_ros builds the request
    assert cam["request"] == {"package_name": "cams", "plugin_name": "cams::Camera",
                              "node_name": "cam", "node_namespace": "/robot",
                              "remap_rules": ["image:=image_raw", "info:=camera_info"]}
    assert cam["full_name"] == "/robot/cam"
    assert cam["container"] == "/robot/containers/box"
    assert cam["parameters"] == {"use_sim_time": True, "everyone": 1, "fps": 15,
                                 "nested.a": 2}
    assert cam["parameter_files"] == [str(params)]
    assert cam["extra_arguments"] == {"use_intra_process_comms": True}
    assert filt["request"]["node_namespace"] == "/abs" and filt["name"] is None
    assert filt["parameters"] == {"use_sim_time": True}


def test_load_composable_nodes_resolves_its_target_and_print_lists_components(write):
    path = write(HEADER + """
def generate_launch_description():
    box = ComposableNodeContainer(name='box', namespace='ns', package='tuilaunch_demos',
                                  executable='component_container')
    return LaunchDescription([
        box,
        LoadComposableNodes(target_container=box, composable_node_descriptions=[
            ComposableNode(package='p', plugin='p::A', name='a')]),
        LoadComposableNodes(target_container='other_container', composable_node_descriptions=[
            ComposableNode(package='p', plugin='p::B', name='b')]),
    ])
""")
    plan = plan_of(path)
    first, second = plan.actions
    assert first.kind == second.kind == "load_components"
    assert first.target == "/ns/box"
    assert second.target == "/other_container"
    assert [c["plugin"] for c in first.data] == ["p::A"]
    out = run_cli(str(path), "--print")
    assert out.returncode == 0, out.stderr
    assert "load components into /ns/box" in out.stdout
    assert "component /a (p::A)" in out.stdout
    data = json.loads(run_cli(str(path), "--print", "--json").stdout)
    assert data["actions"][0]["data"][0]["request"]["plugin_name"] == "p::A"


def test_print_shows_each_component_and_whether_it_can_load(write, composition_interfaces):
    path = str(write(CONTAINER))
    out = run_cli(path, "--print", env={"PYTHONPATH": ""})
    assert out.returncode == 0, out.stderr
    assert "component /talker_c (tuilaunch_demos::Talker)" in out.stdout
    assert "component /broken (tuilaunch_demos::Nothing)" in out.stdout
    assert "component /listener_c (tuilaunch_demos::Listener)" in out.stdout
    assert ("warning: composition_interfaces is not installed: the 3 component(s) of this "
            "launch will not load") in out.stdout
    found = run_cli(path, "--print", env=with_interfaces(composition_interfaces))
    assert "composition_interfaces" not in found.stdout


def test_a_missing_parameter_file_fails_only_that_component(write, tmp_path):
    plan = plan_of(write(HEADER + """
def generate_launch_description():
    return LaunchDescription([ComposableNodeContainer(
        name='box', namespace='', package='tuilaunch_demos', executable='component_container',
        composable_node_descriptions=[
            ComposableNode(package='p', plugin='p::A', name='a', parameters=['/no/such.yaml']),
            ComposableNode(package='p', plugin='p::B', name='b')])])
"""))
    a, b = plan.processes[0].components
    assert a["error"] == "parameter file /no/such.yaml does not exist"
    assert b["error"] is None


# --- a real container -----------------------------------------------------------------------


def test_components_load_into_a_real_container_with_results(write, composition_interfaces):
    out = run_headless(write(CONTAINER), until=("I heard", "could not load", "unique id 2"),
                       env=with_interfaces(composition_interfaces))
    assert "[INFO] [box-1]: loaded /talker_c (tuilaunch_demos::Talker) into /box, unique id 1" \
        in out, out
    # the container's own error, and the file and line of the component
    assert re.search(r"\[ERROR\] \[box-1\]: /box could not load tuilaunch_demos::Nothing into "
                     r"/box \(\S*test_launch\.py:18\): Failed to find class with the "
                     r"requested plugin name\.", out), out
    assert "[INFO] [load_components-1]: loaded /listener_c (tuilaunch_demos::Listener) into " \
        "/box, unique id 2" in out
    startup = next(json.loads(line.split("STARTUP ", 1)[1]) for line in out.splitlines()
                   if "STARTUP" in line and "talker_c" in line)
    assert startup["parameters"]["message"] == "from a component"
    assert 'I heard: "from a component' in out


def test_without_composition_interfaces_each_component_says_so(write):
    env = {"PYTHONPATH": os.environ.get("PYTHONPATH", "")}  # never the built package
    out = run_headless(write(CONTAINER), until=("Listener into",), env=env)
    for plugin, line in (("Talker", 13), ("Nothing", 18), ("Listener", 22)):
        assert re.search(rf"cannot load tuilaunch_demos::{plugin} into /box \(\S*"
                         rf"test_launch\.py:{line}\): composition_interfaces is not installed",
                         out), out


async def test_a_restarted_or_respawned_container_gets_its_components_back(
        write, tmp_path, composition_interfaces, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", with_interfaces(composition_interfaces)["PYTHONPATH"])
    # its own parameter folder: a run removes its folder at the end
    plan = resolve(load_file(str(write(CONTAINER))), {}, tmp_path / "params")
    (box,) = plan.processes
    supervisor = make_supervisor(plan, tmp_path / "log", sigterm_timeout=3)
    loaded: asyncio.Queue[str] = asyncio.Queue()

    def on_event(event: Event) -> None:
        if event.kind == "component" and event.data and event.data["state"] == "loaded":
            loaded.put_nowait(event.data["node"])

    supervisor.subscribe(on_event)
    run = asyncio.ensure_future(supervisor.run(keep_alive=True))

    async def two_loaded() -> set[str]:
        return {await asyncio.wait_for(loaded.get(), 60) for _ in range(2)}

    try:
        assert await two_loaded() == {"/talker_c", "/listener_c"}
        await supervisor.restart(box.id)
        assert await two_loaded() == {"/talker_c", "/listener_c"}
        pid = supervisor.running[box.id].process.pid
        os.killpg(pid, signal.SIGKILL)  # a crash: respawn=True brings it back
        assert await two_loaded() == {"/talker_c", "/listener_c"}
        assert supervisor.retries[box.id] == 1
        results = supervisor.components.results
        assert results["box-1.1"]["unique_id"] == 1  # a fresh container numbers from 1
    finally:
        await supervisor.shutdown("test over")
        await asyncio.wait_for(run, 30)


def test_the_example_runs_lifecycle_nodes_and_components(composition_interfaces):
    example = Path(__file__).resolve().parents[2] / "examples" / "launch" / \
        "lifecycle_and_components_launch.py"
    out = run_headless(example, env=with_interfaces(composition_interfaces), until=(
        "[INFO] [talker-1]: lifecycle state active", "[INFO] [auto-2]: lifecycle state active",
        "loaded /composition/talker", "loaded /composition/listener",
        '[composition.listener]: I heard: "component'))
    assert "talker is inactive: activating it" in out
    assert "[INFO] [container-3]: loaded /composition/talker (tuilaunch_demos::Talker) into " \
        "/composition/container, unique id 1" in out, out
    assert '[composition.listener]: I heard: "component' in out


def test_components_loaded_on_the_container_start_event_load_once(write, composition_interfaces):
    path = write(HEADER + """
from launch.actions import RegisterEventHandler
from launch.event_handlers import OnProcessStart

def generate_launch_description():
    box = ComposableNodeContainer(name='box', namespace='', package='tuilaunch_demos',
                                  executable='component_container')
    load = LoadComposableNodes(target_container=box, composable_node_descriptions=[
        ComposableNode(package='tuilaunch_demos', plugin='tuilaunch_demos::Talker', name='t',
                       parameters=[{'rate': 20.0}]),
        ComposableNode(package='tuilaunch_demos', plugin='tuilaunch_demos::Listener',
                       name='l')])
    return LaunchDescription([
        box, RegisterEventHandler(OnProcessStart(target_action=box, on_start=[load]))])
""")
    out = run_headless(path, env=with_interfaces(composition_interfaces),
                       until=("unique id 1", "unique id 2", "[l]: I heard", "hello 5"))
    assert out.count("]: loaded ") == 2, out
    assert "unique id 3" not in out


def test_parameter_files_with_substitutions_and_set_parameters_from_file(write, tmp_path):
    scoped = tmp_path / "scoped.yaml"
    scoped.write_text("/**:\n  ros__parameters:\n    from_scope: 1\n    fps: 5\n")
    templated = tmp_path / "templated.yaml"
    templated.write_text("cam:\n  ros__parameters:\n    fps: $(var fps)\n    frame: $(var frame)\n")
    plan = plan_of(write(HEADER + f"""
from launch_ros.actions import SetParametersFromFile
from launch_ros.descriptions import ParameterFile
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('fps', default_value='30'),
        DeclareLaunchArgument('frame', default_value='camera_link'),
        SetParametersFromFile('{scoped}'),
        ComposableNodeContainer(
            name='box', namespace='', package='tuilaunch_demos',
            executable='component_container', composable_node_descriptions=[
                ComposableNode(package='cams', plugin='cams::Camera', name='cam',
                               parameters=[ParameterFile('{templated}', allow_substs=True)])]),
    ])
"""), fps=60)
    (cam,) = plan.processes[0].components
    # the scope's file first, then the component's own, its $(var ...) performed
    assert cam["parameters"] == {"from_scope": 1, "fps": 60, "frame": "camera_link"}
    assert cam["parameter_files"] == [str(scoped), str(templated)]


def _exit_status_after(path: Path, env: dict[str, str], text: str) -> tuple[int, str]:
    """Runs headless until `text` is printed, then Ctrl+C: the exit status and the output."""
    import subprocess

    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, **env}, start_new_session=True)
    assert proc.stdout is not None
    seen = ""
    try:
        for line in proc.stdout:
            seen += line
            if text in line:
                break
        proc.send_signal(signal.SIGINT)
        seen += proc.communicate(timeout=120)[0]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return proc.returncode, seen


ONE_COMPONENT = HEADER + """
def generate_launch_description():
    container = ComposableNodeContainer(
        name='box', namespace='', package='tuilaunch_demos', executable='component_container',
        composable_node_descriptions=[{listed}])
    return LaunchDescription([container, LoadComposableNodes(
        target_container=container, composable_node_descriptions=[{loaded}])])
"""


def test_the_exit_status_says_a_component_failed_wherever_it_was_given(
        write, composition_interfaces):
    """A component the container could not load ends the launch non-zero, whether the
    container lists it or a LoadComposableNodes action loads it."""
    good = "ComposableNode(package='tuilaunch_demos', plugin='tuilaunch_demos::Talker', " \
        "name='t{}')"
    bad = "ComposableNode(package='tuilaunch_demos', plugin='tuilaunch_demos::Nothing', " \
        "name='broken')"
    env = with_interfaces(composition_interfaces)
    for listed, loaded, expected in ((bad, good.format(2), 1), (good.format(1), bad, 1),
                                     (good.format(1), good.format(2), 0)):
        path = write(ONE_COMPONENT.format(listed=listed, loaded=loaded))
        last = "unique id 2" if expected == 0 else "could not load"
        status, out = _exit_status_after(path, env, last)
        if expected:
            assert "could not load tuilaunch_demos::Nothing" in out, out
        assert status == expected, out
