"""A listener named `monitor` on a topic chosen by whoever includes this file."""

from simple_launch import SimpleLauncher


def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('topic', '/chatter', description='topic the monitor listens to')
    sl.node('tuilaunch_demos', 'listener', name='monitor', remappings={'chatter': sl.arg('topic')})
    return sl.launch_description()
