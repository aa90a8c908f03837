"""Lifecycle nodes and composable nodes with the plain launch_ros API.

`talker` is configured at start and activated once inactive (the ros2 demos pattern);
`auto` uses `autostart`. The container loads two demo nodes as components; the listener
is added by a separate LoadComposableNodes. Loading needs composition_interfaces (a sourced
/opt/ros/jazzy); without it, each component says so.
"""

from launch import LaunchDescription
from launch.actions import EmitEvent, LogInfo, RegisterEventHandler
from launch.events import matches_action
from launch_ros.actions import ComposableNodeContainer, LifecycleNode, LoadComposableNodes
from launch_ros.descriptions import ComposableNode
from launch_ros.event_handlers import OnStateTransition
from launch_ros.events.lifecycle import ChangeState
from lifecycle_msgs.msg import Transition


def generate_launch_description():
    talker = LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker',
                           name='talker', namespace='lifecycle', parameters=[{'rate': 1.0}])
    auto = LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker',
                         name='auto', namespace='lifecycle', autostart=True,
                         parameters=[{'message': 'autostarted', 'rate': 1.0}])
    container = ComposableNodeContainer(
        name='container', namespace='composition', package='tuilaunch_demos',
        executable='component_container', respawn=True,
        composable_node_descriptions=[
            ComposableNode(package='tuilaunch_demos', plugin='tuilaunch_demos::Talker',
                           name='talker', namespace='composition',
                           parameters=[{'message': 'component', 'rate': 1.0}]),
        ])
    return LaunchDescription([
        RegisterEventHandler(OnStateTransition(
            target_lifecycle_node=talker, goal_state='inactive',
            entities=[LogInfo(msg='talker is inactive: activating it'),
                      EmitEvent(event=ChangeState(
                          lifecycle_node_matcher=matches_action(talker),
                          transition_id=Transition.TRANSITION_ACTIVATE))])),
        talker,
        auto,
        EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_action(talker),
                                    transition_id=Transition.TRANSITION_CONFIGURE)),
        container,
        LoadComposableNodes(target_container=container, composable_node_descriptions=[
            ComposableNode(package='tuilaunch_demos', plugin='tuilaunch_demos::Listener',
                           name='listener', namespace='composition')]),
    ])
