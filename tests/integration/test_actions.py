"""`call_service`, `set_parameters` and `log_info` resolve into the plan's actions."""

from __future__ import annotations

from ..conftest import plan_of

HEADER = """from simple_launch import SimpleLauncher
from simple_launch.events import When, OnProcessStart, OnExecutionComplete
"""


def test_service_and_parameter_targets_are_relative_to_the_namespace(write):
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('red', 200)
    with sl.group(ns='turtlesim1'):
        sim = sl.node('tuilaunch_demos', 'service_server', name='sim')
        with sl.group(when=When(sim, OnProcessStart)):
            spawn = sl.call_service('spawn', {'x': 2., 'name': '__ns', 'pose': {'theta': 0.2}},
                                    verbosity='reqres')
        with sl.group(when=When(spawn, OnExecutionComplete)):
            sl.set_parameters('sim', {'background_r': sl.arg('red'), 'gains': [1, 2.5]})
            sl.call_service('/absolute/reset')
    return sl.launch_description()
""")
    plan = plan_of(path, red=120)
    spawn, params, reset = plan.actions
    assert (spawn.kind, spawn.target, spawn.verbosity) == (
        "call_service", "/turtlesim1/spawn", "reqres")
    assert spawn.data == {"x": 2.0, "name": "/turtlesim1", "pose": {"theta": 0.2}}
    assert spawn.trigger is not None and spawn.trigger.target == "sim-1"
    assert (params.kind, params.target) == ("set_parameters", "/turtlesim1/sim")
    assert params.data == {"background_r": 120, "gains": [1.0, 2.5]}
    assert params.trigger is not None and params.trigger.to_json() == {
        "on": "exit", "target": spawn.id, "delay": 0.0}
    assert reset.target == "/absolute/reset" and reset.data == {}


def test_log_info_concatenates_substitutions(write):
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('who', 'world')
    sl.log_info(['hello ', sl.arg('who')])
    return sl.launch_description()
""")
    assert plan_of(path, who="ros").actions[0].data == "hello ros"
