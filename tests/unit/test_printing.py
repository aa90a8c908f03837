"""`--print`'s tree: a ROS node by its node name, an ExecuteProcess (which has no node name:
ros2 launch describes it by its cmd) by its command line."""

from __future__ import annotations

import textwrap

from tuilaunch.cli.printing import format_tree

from ..conftest import plan_of

FILE = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('extra', default_value='false'),
        ExecuteProcess(name='ticker', cmd=['sh', '-c', 'echo tick; sleep 1']),
        ExecuteProcess(cmd=['sleep', '600'], namespace='/far'),
        ExecuteProcess(name='long', cmd=['echo', 'x' * 80]),
        Node(package='tuilaunch_demos', executable='talker', name='talker', namespace='pc'),
        Node(package='tuilaunch_demos', executable='listener', namespace='pc'),
        ExecuteProcess(name='extra', cmd=['sleep', '1'],
                       condition=IfCondition(LaunchConfiguration('extra'))),
    ])
"""


def test_an_execute_process_is_named_by_its_command_a_node_by_its_name(tmp_path):
    path = tmp_path / "mixed.launch.py"
    path.write_text(textwrap.dedent(FILE))
    lines = format_tree(plan_of(path)).splitlines()
    assert lines[1:7] == [
        "├─ $ sh -c 'echo tick; sleep 1'  [ticker-1]",
        "├─ $ sleep 600  [sleep-2]",
        "├─ $ echo " + "x" * 54 + "…  [long-3]",  # cut at 60 characters
        "├─ /pc/talker  [talker-4] (tuilaunch_demos/talker)",
        "├─ /pc/<listener>  [listener-5] (tuilaunch_demos/listener)",
        "└─ (skipped) $ sleep 1  [extra-6] (if $(var extra) = 'false')",
    ]
    assert "  extra-6 $ sleep 1: " in lines[-1]
    assert not any("/ticker" in line or "/<sleep>" in line for line in lines)
