"""The simple_launch README's own examples, as files in examples/launch/."""

from __future__ import annotations

import itertools

import pytest

from tuilaunch.engine import Plan

from ..conftest import EXAMPLES, plan_of

LAUNCH = EXAMPLES / "launch"
BOOLS = ("true", "false")


def running(plan: Plan) -> set[tuple[str, str]]:
    return {(p.namespace, p.package or p.executable) for p in plan.processes if p.enabled}


def comparable(plan: Plan) -> list[tuple]:
    """What a process will do, without ids (numbering differs when branches are skipped)."""
    out = []
    for p in plan.enabled_processes():
        argv = p.cmd[1:p.cmd.index("--ros-args")] if "--ros-args" in p.cmd else p.cmd[1:]
        out.append((p.namespace, p.name, p.package, p.executable, tuple(argv),
                    repr(sorted(p.parameters.items())), repr(p.remappings)))
    return sorted(out)


@pytest.mark.parametrize("use_gui", BOOLS)
def test_launch_with_arguments(use_gui):
    plan = plan_of(LAUNCH / "readme_launch_with_args.py", prefix="turret", x=1, y=2,
                   use_gui=use_gui)
    gui = "joint_state_publisher_gui" if use_gui == "true" else "joint_state_publisher"
    assert running(plan) == {("/turret", "robot_state_publisher"), ("/turret", gui)}
    rsp = plan.enabled_processes()[0]
    assert 'link name="turret/base_link"' in rsp.parameters["robot_description"]
    assert 'xyz="1 2 0"' in rsp.parameters["robot_description"]


CONDITIONAL_ARGS = ("robot1", "robot2", "no_robot2", "rviz")


def expected_conditional(robot1: bool, robot2: bool, no_robot2: bool, rviz: bool) -> set:
    out = set()
    for ns, on in (("/robot1", robot1), ("/robot2", robot2 and not no_robot2)):
        if on:
            out |= {(ns, "robot_state_publisher"), (ns, "joint_state_publisher_gui")}
    if rviz:
        out.add(("/", "rviz2"))
    return out


@pytest.mark.parametrize("values", list(itertools.product(BOOLS, repeat=4)))
def test_conditional_blocks_and_includes_and_their_opaque_twin(values):
    args = dict(zip(CONDITIONAL_ARGS, values, strict=True))
    flags = [v == "true" for v in values]
    substitution = plan_of(LAUNCH / "readme_conditional_includes.py", **args)
    opaque = plan_of(LAUNCH / "readme_conditional_includes_opaque.py", **args)
    assert running(substitution) == expected_conditional(*flags)
    assert comparable(opaque) == comparable(substitution)


def test_robot2_offsets_reach_xacro_through_the_include():
    plan = plan_of(LAUNCH / "readme_conditional_includes.py", robot2_x=4, robot2_y=5)
    robot2 = next(p for p in plan.enabled_processes() if p.namespace == "/robot2"
                  and p.package == "robot_state_publisher")
    assert 'xyz="4 5 0"' in robot2.parameters["robot_description"]


@pytest.mark.parametrize("cond1,cond2", list(itertools.product(BOOLS, repeat=2)))
def test_combining_conditions(cond1, cond2):
    plan = plan_of(LAUNCH / "readme_combining_conditions.py", cond1=cond1, cond2=cond2)
    a, b = cond1 == "true", cond2 == "true"
    expected = {f"/talker_{logic}" for logic, on in (("and", a and b), ("or", a or b)) if on}
    assert {p.full_name for p in plan.enabled_processes()} == expected
    logs = [action.data for action in plan.actions]
    assert logs == [f"and condition is {a and b}", f"or condition is {a or b}"]
