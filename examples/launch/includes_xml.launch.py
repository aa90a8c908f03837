"""A Python launch file including an XML one, passing it an argument."""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, IncludeLaunchDescription
from launch.launch_description_sources import AnyLaunchDescriptionSource
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution, ThisLaunchFileDir


def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('robot', default_value='from_python'),
        IncludeLaunchDescription(
            AnyLaunchDescriptionSource(PathJoinSubstitution([ThisLaunchFileDir(),
                                                             'bringup.launch.xml'])),
            launch_arguments={'robot': LaunchConfiguration('robot'),
                              'listener': 'false'}.items()),
    ])
