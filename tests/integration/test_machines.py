"""`--machines MACHINES.yaml`: reading the file, and placing a real plan's processes."""

from __future__ import annotations

import textwrap

import pytest

from tuilaunch.engine.plan.machines import (
    Machine,
    MachinesError,
    load_machines,
    parse_machines,
    place,
    unused_rules,
)

from ..conftest import plan_of, python_prints

EXAMPLE = """\
machines:
  nuc:
    host: robot1-nuc            # anything ssh accepts
    tuilaunch: /opt/venv/bin/tuilaunch
    setup: /opt/ros/jazzy/setup.bash
    env: {RMW_IMPLEMENTATION: rmw_fastrtps_cpp, ROS_DOMAIN_ID: 7}
  jetson:
    host: ops@jetson.local
placement:
  - match: /far/**
    machine: nuc
  - match: /**/camera
    machine: jetson
  - match: logger-*
    machine: jetson
"""

LAUNCH = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.node('demo_nodes_py', 'talker', name='talker')
    with sl.group(ns='far'):
        sl.node('demo_nodes_py', 'listener', name='listener')
        with sl.group(ns='deep'):
            sl.node('demo_nodes_py', 'talker', name='camera')
    sl.node('demo_nodes_py', 'talker', name='camera')
    sl.add_action(ExecuteProcess(name='logger', cmd=['sleep', '1']))
    return sl.launch_description()
"""


def test_the_issue_example_reads_as_written(tmp_path):
    path = tmp_path / "machines.yaml"
    path.write_text(EXAMPLE)
    machines = load_machines(path)
    assert machines.machines["nuc"] == Machine(
        "nuc", "robot1-nuc", "/opt/venv/bin/tuilaunch", "/opt/ros/jazzy/setup.bash",
        {"RMW_IMPLEMENTATION": "rmw_fastrtps_cpp", "ROS_DOMAIN_ID": "7"},
        machines.machines["nuc"].origin)
    assert machines.machines["jetson"].host == "ops@jetson.local"
    assert machines.machines["jetson"].tuilaunch is None
    assert [(r.match, r.machine) for r in machines.rules] == [
        ("/far/**", "nuc"), ("/**/camera", "jetson"), ("logger-*", "jetson")]


def test_a_real_plan_is_placed_first_match_wins(write):
    plan = plan_of(write(LAUNCH))
    placed = place(plan.processes, parse_machines(EXAMPLE))
    by_name = {p.full_name or p.id: placed[p.id] for p in plan.processes}
    assert by_name == {
        "/talker": None,                 # no rule: here
        "/far/listener": "nuc",          # ** spans one namespace
        "/far/deep/camera": "nuc",       # and several; the first rule wins over /**/camera
        "/camera": "jetson",             # /**/ matches the root namespace too
        "/logger": "jetson",             # a process id glob (ExecuteProcess logger-N)
    }


@pytest.mark.parametrize("pattern, name, placed", [
    ("/far/*", "/far/a", True),
    ("/far/*", "/far/b/a", False),          # * stays in one segment
    ("/far/**", "/far/b/a", True),
    ("/far/**", "/far", False),
    ("/**", "/anything/at/all", True),
    ("/**/cam?", "/x/y/cam1", True),
    ("/**/cam?", "/cam12", False),
    ("/robot[1]/x", "/robot[1]/x", True),    # no character classes: brackets are literal
])
def test_node_name_globs(pattern, name, placed):
    machines = parse_machines(f"machines: {{m: {{host: h}}}}\nplacement: [{{match: '{pattern}', "
                              "machine: m}]\n")

    class Proc:
        id = "p-1"
        full_name = name

    assert (place([Proc()], machines)["p-1"] == "m") is placed


def test_a_rule_that_places_nothing_is_found(write):
    plan = plan_of(write(LAUNCH))
    machines = parse_machines(EXAMPLE + "  - match: /nowhere/**\n    machine: nuc\n")
    assert [r.match for r in unused_rules(plan.processes, machines)] == ["/nowhere/**"]


@pytest.mark.parametrize("text, says", [
    ("machines:\n  nuc:\n    hots: x\n", "m.yaml:3:5: machines.nuc: unknown field 'hots'"),
    ("machines:\n  nuc:\n    tuilaunch: x\n", "m.yaml:3:5: machines.nuc: no 'host:'"),
    ("machines:\n  nuc: {host: [a, b]}\n", "m.yaml:2:15: machines.nuc.host must be a single"),
    ("machines:\n  nuc: {host: -oProxyCommand=x}\n", "m.yaml:2:15: machines.nuc.host "
     "'-oProxyCommand=x' is not a host"),
    ("machines:\n  nuc: {host: h, env: {1X: y}}\n", "m.yaml:2:24: machines.nuc.env: '1X' is "
     "not a variable name"),
    ("machines:\n  nuc: {host: h}\nplacement:\n  - match: /a/**\n    machine: nux\n",
     "m.yaml:5:14: placement.machine 'nux' is not among the machines"),
    ("machines:\n  nuc: {host: h}\nplacement:\n  - match: /a/**\n",
     "m.yaml:4:5: placement item: no 'machine:'"),
    ("machines:\n  nuc: {host: h}\nplacement: {match: x}\n",
     "m.yaml:3:12: placement: must be a list"),
    ("machines:\n  nuc: {host: h}\n  nuc: {host: i}\n", "m.yaml:3:3: machines: 'nuc' is given "
     "twice"),
    ("placement: []\n", "m.yaml:1:1: no 'machines:'"),
    ("machines: [nuc]\n", "m.yaml:1:11: machines must be a mapping"),
    ("machines:\n  nuc: {host: h\n", "m.yaml:3:1: not YAML"),
    ("machines:\n  'a b': {host: h}\n", "m.yaml:2:3: machine name 'a b' is not usable"),
])
def test_each_mistake_is_one_line_naming_file_line_and_field(text, says):
    with pytest.raises(MachinesError) as caught:
        parse_machines(text, "m.yaml")
    assert str(caught.value).split("\n")[0].startswith(says), str(caught.value)


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(MachinesError, match=r"machines file .*nope\.yaml: No such file"):
        load_machines(tmp_path / "nope.yaml")


def test_the_plan_layer_reads_it_without_the_run_layer():
    """Placement is plan data: reading a machines file imports nothing that runs."""
    code = textwrap.dedent("""
        import sys, tuilaunch.engine.plan.machines
        bad = sorted(m for m in sys.modules if m.startswith(('tuilaunch.engine.run',
                                                            'textual')))
        print(bad); sys.exit(1 if bad else 0)
    """)
    python_prints(code)
