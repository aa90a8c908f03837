"""Files written with the plain launch API map onto the same Description and Plan."""

from __future__ import annotations

from ..conftest import plan_of

PLAIN = """
from launch import LaunchDescription
from launch.actions import (DeclareLaunchArgument, GroupAction, IncludeLaunchDescription,
                            LogInfo, RegisterEventHandler, TimerAction, SetEnvironmentVariable)
from launch.conditions import IfCondition, UnlessCondition
from launch.event_handlers import OnProcessExit, OnProcessStart
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution, PythonExpression
from launch_ros.actions import Node, PushRosNamespace, SetParameter, SetRemap
from launch_ros.substitutions import FindPackageShare


def generate_launch_description():
    robot = LaunchConfiguration('robot')
    talker = Node(package='tuilaunch_demos', executable='talker', name='talker',
                  parameters=[{'rate': LaunchConfiguration('rate')}])
    return LaunchDescription([
        DeclareLaunchArgument('robot', default_value='r1', description='robot name'),
        DeclareLaunchArgument('rate', default_value='2.0'),
        DeclareLaunchArgument('debug', default_value='false', choices=['true', 'false']),
        SetEnvironmentVariable('RCUTILS_COLORIZED_OUTPUT', '1'),
        GroupAction([
            PushRosNamespace(robot),
            SetParameter(name='use_sim_time', value=False),
            SetRemap(src='chatter', dst='news'),
            talker,
            Node(package='tuilaunch_demos', executable='listener',
                 condition=UnlessCondition(LaunchConfiguration('debug'))),
            IncludeLaunchDescription(
                PythonLaunchDescriptionSource(PathJoinSubstitution(
                    [FindPackageShare('tuilaunch_demos'), 'launch', 'monitor.launch.py'])),
                launch_arguments={'topic': 'news'}.items()),
        ]),
        GroupAction([LogInfo(msg='debug mode')],
                    condition=IfCondition(PythonExpression(["'", LaunchConfiguration('debug'),
                                                            "' == 'true'"]))),
        RegisterEventHandler(OnProcessStart(target_action=talker, on_start=[
            TimerAction(period=0.5, actions=[
                Node(package='tuilaunch_demos', executable='configurable')])])),
        RegisterEventHandler(OnProcessExit(target_action=talker, on_exit=[
            LogInfo(msg='talker is gone')])),
    ])
"""


def test_plain_launch_api_file(write):
    path = write(PLAIN)
    plan = plan_of(path, robot="r5")
    talker, listener, monitor, configurable = plan.processes
    assert talker.full_name == "/r5/talker"
    assert talker.parameters == {"use_sim_time": False, "rate": 2.0}
    assert talker.remappings == [["chatter", "news"]]
    assert talker.env == {"RCUTILS_COLORIZED_OUTPUT": "1"}
    assert listener.enabled and listener.namespace == "/r5"
    assert monitor.full_name == "/r5/monitor" and monitor.remappings[-1] == ["chatter", "news"]
    assert configurable.namespace == "/"  # the group's namespace does not reach the handler
    assert configurable.trigger is not None and configurable.trigger.to_json() == {
        "on": "timer", "target": None, "delay": 0.5,
        "after": {"on": "start", "target": talker.id, "delay": 0.0}}
    logs = {a.data: a for a in plan.actions}
    assert not logs["debug mode"].enabled
    assert logs["talker is gone"].trigger is not None
    assert logs["talker is gone"].trigger.on == "exit"
    debug = plan_of(path, debug="true")
    assert not debug.processes[1].enabled and debug.actions[0].enabled


def test_opaque_function_of_the_plain_api(write):
    path = write("""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

def setup(context, *args, **kwargs):
    count = int(LaunchConfiguration('count').perform(context))
    return [Node(package='tuilaunch_demos', executable='talker', name=f't{i}')
            for i in range(count)]

def generate_launch_description():
    return LaunchDescription([DeclareLaunchArgument('count', default_value='2'),
                              OpaqueFunction(function=setup)])
""")
    assert [p.name for p in plan_of(path, count=3).processes] == ["t0", "t1", "t2"]


def test_the_keywords_of_dashing_are_taken_as_docs_launch_files_says(write):
    """docs/launch-files.md, "what differs on purpose": `node_executable`, `node_name` and
    `node_namespace` (Dashing, Eloquent) mean `executable`, `name` and `namespace`, which
    launch_ros since Galactic refuses."""
    path = write("""
from launch import LaunchDescription
from launch_ros.actions import Node

def generate_launch_description():
    return LaunchDescription([Node(package='tuilaunch_demos', node_executable='talker',
                                   node_name='old_talker', node_namespace='r1')])
""")
    (proc,) = plan_of(path).processes
    assert (proc.name, proc.namespace) == ("old_talker", "/r1")
    assert proc.cmd[0].endswith("talker")
