"""tuilaunch's demo bringup: one robot's nodes in its namespace, with optional parts.

    tuilaunch examples/bringup.py robot:=r2 listener:=false
"""

from simple_launch import SimpleLauncher
from simple_launch.events import OnProcessStart, When


def generate_launch_description():
    sl = SimpleLauncher()

    sl.declare_arg('robot', 'r1', description='robot name, used as the namespace of its nodes')
    sl.declare_arg('rate', 2.0, description='talker publishing rate [Hz]')
    sl.declare_arg('listener', True, description='run a listener beside the talker')
    sl.declare_arg('services', True, description='run the service server and reset it at start')
    sl.declare_arg('mode', 'patrol', description='mode given to the configurable node',
                   choices=['idle', 'patrol', 'dock'])

    with sl.group(ns=sl.arg('robot')):
        talker = sl.node('tuilaunch_demos', 'talker',
                         parameters={'rate': sl.arg('rate'), 'message': sl.arg('robot') + ' says hi'})

        with sl.group(if_arg='listener'):
            sl.node('tuilaunch_demos', 'listener')

        # started one second after the talker, then reconfigured through its parameter service
        with sl.group(ns='control', when=When(talker, OnProcessStart, 1.0)):
            sl.node('tuilaunch_demos', 'configurable', parameters={'mode': 'idle'})
            sl.set_parameters('configurable', {'mode': sl.arg('mode')}, verbosity='res')

        with sl.group(if_arg='services'):
            server = sl.node('tuilaunch_demos', 'service_server')
            with sl.group(when=When(server, OnProcessStart)):
                sl.call_service('reset', verbosity='res')

        sl.include('tuilaunch_demos', 'monitor.launch.py',
                   launch_arguments={'topic': 'chatter'})

    return sl.launch_description()
