"""Launch files in the style of real robots' bringups (nav2_bringup, turtlebot3, multi-robot
simulation, rviz with a namespaced config), written for these tests, against probe
executables in a test ament prefix: the plan and the run match what ros2 launch does."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
import yaml

from ..conftest import run_cli
from .launch_world import install_extension, make_package, probe_records, world_env

COMMON = """
import os
from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import (AppendEnvironmentVariable, DeclareLaunchArgument, EmitEvent,
                            ExecuteProcess, GroupAction, IncludeLaunchDescription, LogInfo,
                            OpaqueFunction, RegisterEventHandler, SetEnvironmentVariable)
from launch.conditions import IfCondition, UnlessCondition
from launch.event_handlers import OnProcessExit, OnShutdown
from launch.events import Shutdown
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import (EqualsSubstitution, LaunchConfiguration, NotEqualsSubstitution,
                                  PythonExpression, TextSubstitution)
from launch_ros.actions import LoadComposableNodes, Node, PushROSNamespace, SetParameter
from launch_ros.descriptions import ComposableNode, ParameterFile
from fake_nav_common.launch import ReplaceText, RewrittenParams, RobotPoses

share = get_package_share_directory('fake_nav_bringup')
launch_dir = os.path.join(share, 'launch')
"""

DECLARES = """
def declares(**extra):
    defaults = dict(namespace='', use_sim_time='false', autostart='true',
                    params_file=os.path.join(share, 'params', 'nav_params.yaml'),
                    use_composition='False', use_respawn='False', log_level='info',
                    container_name='nav_container', slam='False', map='',
                    use_localization='True', use_namespace='false', use_rviz='False')
    defaults.update(extra)
    return [DeclareLaunchArgument(k, default_value=v) for k, v in defaults.items()]

def params():
    return ParameterFile(RewrittenParams(
        source_file=LaunchConfiguration('params_file'), root_key=LaunchConfiguration('namespace'),
        param_rewrites={'use_sim_time': LaunchConfiguration('use_sim_time'),
                        'autostart': LaunchConfiguration('autostart')},
        convert_types=True), allow_substs=True)
"""

FILES = {
    "params/nav_params.yaml": """
        amcl:
          ros__parameters:
            use_sim_time: false
            base_frame_id: base_footprint
            scan_topic: scan
        controller_server:
          ros__parameters:
            use_sim_time: false
            controller_frequency: 20.0
        map_server:
          ros__parameters:
            yaml_filename: $(var map)
        lifecycle_manager_localization:
          ros__parameters:
            autostart: false
        """,
    "rviz/view.rviz": "Panels: []\nTopic: <robot_namespace>/map\n",
    "launch/navigation_launch.py": COMMON + DECLARES + """
def generate_launch_description():
    remappings = [('/tf', 'tf'), ('/tf_static', 'tf_static')]
    nodes = GroupAction(condition=IfCondition(PythonExpression(['not ',
                        LaunchConfiguration('use_composition')])), actions=[
        SetParameter('use_sim_time', LaunchConfiguration('use_sim_time')),
        Node(package='fake_nav', executable='controller_server', output='screen',
             respawn=LaunchConfiguration('use_respawn'), respawn_delay=2.0,
             parameters=[params()],
             arguments=['--ros-args', '--log-level', LaunchConfiguration('log_level')],
             remappings=remappings + [('cmd_vel', 'cmd_vel_nav')]),
        Node(package='fake_nav', executable='lifecycle_manager',
             name='lifecycle_manager_navigation',
             parameters=[{'autostart': LaunchConfiguration('autostart'),
                          'node_names': ['controller_server']}]),
    ])
    composed = GroupAction(condition=IfCondition(LaunchConfiguration('use_composition')),
                           actions=[
        SetParameter('use_sim_time', LaunchConfiguration('use_sim_time')),
        LoadComposableNodes(
            target_container=(LaunchConfiguration('namespace'), '/',
                              LaunchConfiguration('container_name')),
            composable_node_descriptions=[ComposableNode(
                package='fake_nav', plugin='nav::ControllerServer', name='controller_server',
                parameters=[params()], remappings=remappings)]),
    ])
    return LaunchDescription([SetEnvironmentVariable('RCUTILS_LOGGING_BUFFERED_STREAM', '1')]
                             + declares() + [nodes, composed])
""",
    "launch/localization_launch.py": COMMON + DECLARES + """
def generate_launch_description():
    return LaunchDescription(declares() + [GroupAction(
        condition=IfCondition(PythonExpression(['not ', LaunchConfiguration('use_composition')])),
        actions=[
            SetParameter('use_sim_time', LaunchConfiguration('use_sim_time')),
            Node(condition=IfCondition(EqualsSubstitution(LaunchConfiguration('map'), '')),
                 package='fake_nav', executable='map_server', name='map_server',
                 parameters=[params()]),
            Node(condition=IfCondition(NotEqualsSubstitution(LaunchConfiguration('map'), '')),
                 package='fake_nav', executable='map_server', name='map_server',
                 parameters=[params(), {'yaml_filename': LaunchConfiguration('map')}]),
            Node(package='fake_nav', executable='amcl', name='amcl', parameters=[params()]),
            Node(package='fake_nav', executable='lifecycle_manager',
                 name='lifecycle_manager_localization', parameters=[params(),
                 {'autostart': LaunchConfiguration('autostart'),
                  'node_names': ['map_server', 'amcl']}]),
        ])])
""",
    "launch/slam_launch.py": COMMON + DECLARES + """
def generate_launch_description():
    return LaunchDescription(declares() + [
        Node(package='fake_nav', executable='slam', name='slam_toolbox',
             parameters=[params(), {'use_sim_time': LaunchConfiguration('use_sim_time')}])])
""",
    "launch/rviz_launch.py": COMMON + DECLARES + """
def generate_launch_description():
    config = os.path.join(share, 'rviz', 'view.rviz')
    plain = Node(condition=UnlessCondition(LaunchConfiguration('use_namespace')),
                 package='fake_nav', executable='rviz2', arguments=['-d', config])
    namespaced = Node(condition=IfCondition(LaunchConfiguration('use_namespace')),
                      package='fake_nav', executable='rviz2',
                      namespace=LaunchConfiguration('namespace'),
                      arguments=['-d', ReplaceText(config, {'<robot_namespace>': (
                          '/', LaunchConfiguration('namespace'))},
                          condition=IfCondition(LaunchConfiguration('use_namespace')))],
                      remappings=[('/map', 'map')])
    return LaunchDescription(declares() + [plain, namespaced,
        RegisterEventHandler(condition=UnlessCondition(LaunchConfiguration('use_namespace')),
            event_handler=OnProcessExit(target_action=plain,
                on_exit=EmitEvent(event=Shutdown(reason='rviz exited')))),
        RegisterEventHandler(condition=IfCondition(LaunchConfiguration('use_namespace')),
            event_handler=OnProcessExit(target_action=namespaced,
                on_exit=EmitEvent(event=Shutdown(reason='rviz exited'))))])
""",
    "launch/bringup_launch.py": COMMON + DECLARES + """
def include(name, **args):
    return IncludeLaunchDescription(
        PythonLaunchDescriptionSource(os.path.join(launch_dir, name)),
        condition=args.pop('condition', None),
        launch_arguments={k: LaunchConfiguration(k) for k in (
            'namespace', 'use_sim_time', 'autostart', 'params_file', 'use_composition',
            'use_respawn', 'map')}.items())

def generate_launch_description():
    slam = LaunchConfiguration('slam')
    loc = LaunchConfiguration('use_localization')
    return LaunchDescription(declares() + [GroupAction([
        PushROSNamespace(LaunchConfiguration('namespace')),
        Node(condition=IfCondition(LaunchConfiguration('use_composition')),
             name='nav_container', package='fake_nav', executable='container',
             parameters=[params(), {'autostart': LaunchConfiguration('autostart')}],
             arguments=['--ros-args', '--log-level', LaunchConfiguration('log_level')]),
        include('slam_launch.py', condition=IfCondition(PythonExpression([slam, ' and ', loc]))),
        include('localization_launch.py',
                condition=IfCondition(PythonExpression(['not ', slam, ' and ', loc]))),
        include('navigation_launch.py'),
    ])])
""",
    "launch/sim_launch.py": COMMON + DECLARES + """
import tempfile

def generate_launch_description():
    world_file = tempfile.mktemp(prefix='navtest_', suffix='.sdf')
    with open(world_file, 'w') as handle:
        handle.write('<sdf/>')
    print('world in', world_file)
    make_world = ExecuteProcess(cmd=['sh', '-c', ['echo world > ', world_file]])
    return LaunchDescription(declares(robot_name='tb3', x_pose='0.0') + [
        make_world,
        RegisterEventHandler(event_handler=OnShutdown(on_shutdown=[
            OpaqueFunction(function=lambda _: os.remove(world_file)),
            LogInfo(msg=['removed ', world_file])])),
        Node(package='fake_nav', executable='robot_state_publisher',
             namespace=LaunchConfiguration('namespace'),
             parameters=[{'robot_description': LaunchConfiguration('robot_name'),
                          'use_sim_time': LaunchConfiguration('use_sim_time')}]),
        Node(package='fake_nav', executable='spawn', arguments=[
            '-name', LaunchConfiguration('robot_name'), '-x', LaunchConfiguration('x_pose')]),
        IncludeLaunchDescription(PythonLaunchDescriptionSource(
            os.path.join(launch_dir, 'bringup_launch.py')),
            launch_arguments={'namespace': LaunchConfiguration('namespace'),
                              'use_sim_time': 'True'}.items()),
    ])
""",
    "launch/multi_launch.py": COMMON + DECLARES + """
def generate_launch_description():
    robots = RobotPoses('robots').value()
    groups = []
    for name, pose in robots.items():
        groups.append(GroupAction([
            LogInfo(msg=['Launching namespace=', name, ' init_pose=', str(pose)]),
            IncludeLaunchDescription(
                PythonLaunchDescriptionSource(os.path.join(launch_dir, 'sim_launch.py')),
                launch_arguments={'namespace': name, 'robot_name': TextSubstitution(text=name),
                                  'x_pose': TextSubstitution(text=str(pose['x']))}.items()),
        ]))
    return LaunchDescription(declares() + [
        AppendEnvironmentVariable('PROBE_RESOURCES', os.path.join(share, 'models')),
        AppendEnvironmentVariable('PROBE_RESOURCES', share),
    ] + groups)
""",
}

EXES = ["controller_server", "lifecycle_manager", "map_server", "amcl", "slam", "rviz2",
        "container", "robot_state_publisher", "spawn"]


@pytest.fixture
def nav_world(tmp_path):
    prefix = tmp_path / "prefix"
    make_package(prefix, "fake_nav", EXES)
    make_package(prefix, "fake_nav_bringup", files=FILES)
    ext = install_extension(tmp_path / "ext")
    probes = tmp_path / "probes"
    probes.mkdir()
    return world_env(prefix, ext, probes), probes


# `--print --json` in a child, which also reads the parameter files the plan names before
# it exits: the files generated for a plan live in a private folder removed at exit
PRINT_AND_READ = """
import contextlib, io, json, sys
from tuilaunch.cli import main
out = io.StringIO()
with contextlib.redirect_stdout(out):
    status = main(sys.argv[1:])
plan = json.loads(out.getvalue())
files = {path: open(path).read() for p in plan["processes"] for path in p["parameter_files"]}
print(json.dumps({"status": status, "plan": plan, "files": files}))
"""


def print_json(env, *args):
    done = subprocess.run([sys.executable, "-c", PRINT_AND_READ, "fake_nav_bringup", *args,
                           "--print", "--json"], capture_output=True, text=True, timeout=60,
                          env={**os.environ, **env})
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    assert result["status"] == 0, done.stderr
    for process in result["plan"]["processes"]:
        process["file_contents"] = [result["files"][p] for p in process["parameter_files"]]
    return result["plan"], done


def params_of(process) -> dict:
    merged: dict = {}
    for text in process["file_contents"]:
        merged.update(yaml.safe_load(text))
    return merged


def test_bringup_plans_the_nodes_names_namespaces_and_rewritten_parameters(nav_world):
    env, _ = nav_world
    plan, _ = print_json(env, "bringup_launch.py", "namespace:=r1", "use_sim_time:=true",
                         "map:=/maps/office.yaml")
    names = sorted(p["namespace"] + "/" + (p["name"] or p["executable"])
                   for p in plan["processes"] if p["enabled"])
    assert names == ["/r1/amcl", "/r1/controller_server", "/r1/lifecycle_manager_localization",
                     "/r1/lifecycle_manager_navigation", "/r1/map_server"]
    amcl = next(p for p in plan["processes"] if p["name"] == "amcl")
    rewritten = params_of(amcl)
    # the rewritten file is nested under the namespace, values rewritten and typed
    assert rewritten["r1"]["amcl"]["ros__parameters"] == {
        "use_sim_time": True, "base_frame_id": "base_footprint", "scan_topic": "scan"}
    assert rewritten["r1"]["map_server"]["ros__parameters"]["yaml_filename"] == \
        "/maps/office.yaml"  # allow_substs performed $(var map) inside the file
    controller = next(p for p in plan["processes"] if p["executable"] == "controller_server")
    assert controller["parameters"] == {"use_sim_time": True}  # SetParameter
    cmd = controller["cmd"]
    assert cmd[1:4] == ["--ros-args", "--log-level", "info"]
    assert ["cmd_vel", "cmd_vel_nav"] in controller["remappings"]
    assert ["/tf", "tf"] in controller["remappings"]
    assert controller["respawn"] is False
    maps = [p for p in plan["processes"] if p["name"] == "map_server"]
    assert [m["enabled"] for m in maps] == [False, True]
    assert controller["env"]["RCUTILS_LOGGING_BUFFERED_STREAM"] == "1"


def test_bringup_with_slam_and_composition(nav_world):
    env, _ = nav_world
    plan, _ = print_json(env, "bringup_launch.py", "slam:=True", "use_composition:=True")
    enabled = sorted((p["name"] or p["executable"]) for p in plan["processes"] if p["enabled"])
    assert enabled == ["nav_container", "slam_toolbox"]
    (load,) = [a for a in plan["actions"] if a["kind"] == "load_components" and a["enabled"]]
    assert load["data"][0]["plugin"] == "nav::ControllerServer"


def test_rviz_with_namespace_reads_a_rewritten_config_and_shutdown_on_exit(nav_world):
    env, probes = nav_world
    plan, _ = print_json(env, "rviz_launch.py", "namespace:=r2", "use_namespace:=true")
    (rviz,) = [p for p in plan["processes"] if p["enabled"]]
    assert rviz["namespace"] == "/r2"
    config = rviz["cmd"][rviz["cmd"].index("-d") + 1]
    assert open(config).read() == "Panels: []\nTopic: /r2/map\n"
    done = run_cli("fake_nav_bringup", "rviz_launch.py", "--headless", env=env)
    # EmitEvent(Shutdown(reason=...)) ends it without a word, as in ros2 launch
    assert "process has finished cleanly" in done.stdout and "was required" not in done.stdout
    assert [r["exe"] for r in probe_records(probes)] == ["rviz2"]


def test_multi_robot_simulation_runs_each_robot_and_cleans_up(nav_world, tmp_path):
    env, probes = nav_world
    args = ("multi_launch.py", "robots:=robot1={x: 0.5};robot2={x: -1.5}")
    plan, printed = print_json(env, *args)
    world_files = [line.split()[-1] for line in printed.stderr.splitlines()
                   if line.startswith("world in")]
    assert len(world_files) == 2  # the file's print() went to stderr, not into the JSON
    logs = [a["data"] for a in plan["actions"] if a["kind"] == "log" and a["enabled"]
            and a["trigger"] is None]
    assert logs == ["Launching namespace=robot1 init_pose={'x': 0.5}",
                        "Launching namespace=robot2 init_pose={'x': -1.5}"]
    spawns = [p["cmd"][1:] for p in plan["processes"] if p["executable"] == "spawn"]
    assert spawns == [["-name", "robot1", "-x", "0.5", "--ros-args"],
                      ["-name", "robot2", "-x", "-1.5", "--ros-args"]]
    rsp = [p for p in plan["processes"] if p["executable"] == "robot_state_publisher"]
    assert [p["namespace"] for p in rsp] == ["/robot1", "/robot2"]
    amcls = [p for p in plan["processes"] if p["name"] == "amcl" and p["enabled"]]
    assert [p["full_name"] for p in amcls] == ["/robot1/amcl", "/robot2/amcl"]
    assert params_of(amcls[1])["robot2"]["amcl"]["ros__parameters"]["use_sim_time"] is True
    assert all(p["env"].get("PROBE_RESOURCES", "").endswith(
        "share/fake_nav_bringup/models:" + p["env"]["PROBE_RESOURCES"].split(":")[-1])
        for p in plan["processes"] if p["enabled"])
    import os
    assert all(os.path.exists(f) for f in world_files)  # --print ran no OnShutdown cleanup
    for f in world_files:
        os.remove(f)

    done = run_cli("fake_nav_bringup", *args, "--headless", env=env, timeout=90)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr
    removed = [line.split()[-1] for line in done.stdout.splitlines() if "removed " in line]
    assert len(removed) == 2 and not any(os.path.exists(f) for f in removed)
    records = probe_records(probes)
    amcl_namespaces = sorted(arg for r in records if r["exe"] == "amcl"
                             for arg in r["argv"] if arg.startswith("__ns:="))
    assert amcl_namespaces == ["__ns:=/robot1", "__ns:=/robot2"]
    assert {r["env"]["PROBE_RESOURCES"] for r in records} == {
        os.pathsep.join([os.path.join(share, "models"), share]) for share in
        [str(tmp_path / "prefix" / "share" / "fake_nav_bringup")]}


TB3_FILES = {
    "param/burger.yaml": """
        turtlebot3_node:
          ros__parameters:
            wheels:
              separation: 0.160
        """,
    "urdf/turtlebot3_burger.urdf": "<robot name='burger'/>\n",
    "launch/robot.launch.py": """
        import os
        from ament_index_python.packages import get_package_share_directory
        from launch import LaunchDescription
        from launch.actions import DeclareLaunchArgument, IncludeLaunchDescription
        from launch.launch_description_sources import PythonLaunchDescriptionSource
        from launch.substitutions import LaunchConfiguration, ThisLaunchFileDir
        from launch_ros.actions import Node

        MODEL = os.environ['PROBE_TB3_MODEL']

        def generate_launch_description():
            use_sim_time = LaunchConfiguration('use_sim_time', default='false')
            usb_port = LaunchConfiguration('usb_port', default='/dev/ttyACM0')
            param_dir = LaunchConfiguration('tb3_param_dir', default=os.path.join(
                get_package_share_directory('fake_tb3'), 'param', MODEL + '.yaml'))
            return LaunchDescription([
                DeclareLaunchArgument('use_sim_time', default_value=use_sim_time),
                DeclareLaunchArgument('usb_port', default_value=usb_port),
                IncludeLaunchDescription(
                    PythonLaunchDescriptionSource([ThisLaunchFileDir(), '/rsp.launch.py']),
                    launch_arguments={'use_sim_time': use_sim_time}.items()),
                Node(package='fake_tb3', executable='turtlebot3_ros',
                     parameters=[param_dir], arguments=['-i', usb_port], output='screen'),
            ])
        """,
    "launch/rsp.launch.py": """
        import os
        from ament_index_python.packages import get_package_share_directory
        from launch import LaunchDescription
        from launch.actions import DeclareLaunchArgument
        from launch.substitutions import Command, LaunchConfiguration
        from launch_ros.actions import Node
        from launch_ros.parameter_descriptions import ParameterValue

        def generate_launch_description():
            urdf_file_name = 'turtlebot3_' + os.environ['PROBE_TB3_MODEL'] + '.urdf'
            print('urdf_file_name : {}'.format(urdf_file_name))
            urdf = os.path.join(get_package_share_directory('fake_tb3'), 'urdf', urdf_file_name)
            return LaunchDescription([
                DeclareLaunchArgument('use_sim_time', default_value='false'),
                Node(package='fake_tb3', executable='robot_state_publisher',
                     name='robot_state_publisher', output='screen',
                     parameters=[{'use_sim_time': LaunchConfiguration('use_sim_time'),
                                  'robot_description': ParameterValue(
                                      Command(['cat ', urdf]), value_type=str)}]),
            ])
        """,
}


def test_turtlebot3_style_bringup(tmp_path):
    prefix = tmp_path / "prefix"
    share = make_package(prefix, "fake_tb3", ["turtlebot3_ros", "robot_state_publisher"],
                         files=TB3_FILES)
    probes = tmp_path / "probes"
    probes.mkdir()
    env = {**world_env(prefix, tmp_path, probes), "PROBE_TB3_MODEL": "burger"}
    done = run_cli("fake_tb3", "robot.launch.py", "use_sim_time:=true", "--print", "--json",
                   env=env)
    assert done.returncode == 0, done.stderr
    assert "urdf_file_name : turtlebot3_burger.urdf" in done.stderr
    plan = json.loads(done.stdout)
    rsp, node = plan["processes"]
    assert rsp["full_name"] == "/robot_state_publisher"
    assert rsp["parameters"] == {"use_sim_time": True,
                                 "robot_description": "<robot name='burger'/>\n"}
    assert node["parameter_files"] == [str(share / "param" / "burger.yaml")]
    assert node["cmd"][1:3] == ["-i", "/dev/ttyACM0"]
    run = run_cli("fake_tb3", "robot.launch.py", "--headless", env=env)
    assert run.returncode == 0, run.stdout + run.stderr
    records = {r["exe"]: r for r in probe_records(probes)}
    assert records["turtlebot3_ros"]["params"][str(share / "param" / "burger.yaml")] == {
        "turtlebot3_node": {"ros__parameters": {"wheels": {"separation": 0.16}}}}
