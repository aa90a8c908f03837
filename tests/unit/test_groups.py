"""`with sl.group(...)`: namespaces compose, conditions combine, triggers nest."""

from __future__ import annotations

import pytest

from tuilaunch.engine import DslError

from ..conftest import enabled_names, plan_of, sl_file

HEADER = """
from simple_launch import SimpleLauncher
from simple_launch.events import When, OnProcessStart, OnProcessExit, OnProcessIO
"""


def test_relative_namespaces_append_and_absolute_ones_reset(write):
    path = write(sl_file("""
    with sl.group(ns='robot'):
        sl.node('tuilaunch_demos', 'talker', name='a')
        with sl.group(ns='arm'):
            sl.node('tuilaunch_demos', 'talker', name='b')
            with sl.group(ns='/absolute'):
                sl.node('tuilaunch_demos', 'talker', name='c')
        sl.node('tuilaunch_demos', 'talker', name='d', namespace='sub')
        sl.node('tuilaunch_demos', 'talker', name='e', namespace='/elsewhere')
    sl.node('tuilaunch_demos', 'talker', name='f')
""", HEADER))
    plan = plan_of(path)
    assert [p.full_name for p in plan.processes] == [
        "/robot/a", "/robot/arm/b", "/absolute/c", "/robot/sub/d", "/elsewhere/e", "/f"]
    assert "__ns:=/robot/arm" in plan.processes[1].cmd


def test_constructor_namespace_applies_inside_and_outside_groups(write):
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher(namespace='fleet')
    sl.node('tuilaunch_demos', 'talker', name='top')
    with sl.group(ns='r1'):
        sl.node('tuilaunch_demos', 'talker', name='inner')
    return sl.launch_description()
""")
    assert [p.full_name for p in plan_of(path).processes] == ["/fleet/top", "/fleet/r1/inner"]


def test_namespace_from_an_argument(write):
    path = write(sl_file("""
    sl.declare_arg('robot', 'r1')
    with sl.group(ns=sl.arg('robot')):
        sl.node('tuilaunch_demos', 'talker', name='t')
""", HEADER))
    assert plan_of(path).processes[0].full_name == "/r1/t"
    assert plan_of(path, robot="r7").processes[0].full_name == "/r7/t"


NESTED = sl_file("""
    sl.declare_arg('outer', True)
    sl.declare_arg('inner', True)
    with sl.group(if_arg='outer'):
        sl.node('tuilaunch_demos', 'talker', name='o')
        with sl.group(unless_arg='inner'):
            sl.node('tuilaunch_demos', 'talker', name='not_inner')
        with sl.group(if_arg='inner'):
            sl.node('tuilaunch_demos', 'talker', name='both')
""", HEADER)


@pytest.mark.parametrize("outer,inner,expected", [
    ("true", "true", {"/o", "/both"}),
    ("true", "false", {"/o", "/not_inner"}),
    ("false", "true", set()),
    ("false", "false", set()),  # an inner group never runs when an outer condition is false
])
def test_nested_conditions_combine(write, outer, inner, expected):
    plan = plan_of(write(NESTED), outer=outer, inner=inner)
    assert enabled_names(plan) == expected


def test_skipped_process_names_the_condition_that_was_false(write):
    plan = plan_of(write(NESTED), outer="false")
    skipped = plan.processes[0].skipped_by
    assert skipped is not None
    assert "outer" in skipped.expression and skipped.value == "false"


def test_if_condition_and_unless_condition_take_raw_values_and_substitutions(write):
    path = write(sl_file("""
    sl.declare_arg('flag', False)
    with sl.group(if_condition=True):
        sl.node('tuilaunch_demos', 'talker', name='raw_true')
    with sl.group(unless_condition=True):
        sl.node('tuilaunch_demos', 'talker', name='raw_false')
    with sl.group(unless_condition=sl.arg('flag')):
        sl.node('tuilaunch_demos', 'talker', name='unless_flag')
    with sl.group(if_arg=sl.py_eval('not ', sl.arg('flag'))):
        sl.node('tuilaunch_demos', 'talker', name='non_string_if_arg')
""", HEADER))
    assert enabled_names(plan_of(path)) == {"/raw_true", "/unless_flag", "/non_string_if_arg"}
    assert enabled_names(plan_of(path, flag="true")) == {"/raw_true"}


def test_a_group_takes_only_one_condition(write):
    path = write(sl_file("""
    sl.declare_arg('a', True)
    with sl.group(if_arg='a', unless_arg='a'):
        pass
""", HEADER))
    from tuilaunch.engine import load_file

    with pytest.raises(DslError) as info:
        load_file(str(path))
    assert "one condition" in str(info.value) and f"{path}:8" in str(info.value)


def test_event_groups_nest_and_wait_for_their_events(write):
    path = write(sl_file("""
    sl.declare_arg('delay', 4.0)
    main = sl.node('tuilaunch_demos', 'talker', name='main')
    with sl.group(when=When(main, OnProcessStart, 1.)):
        other = sl.node('tuilaunch_demos', 'talker', name='other')
        with sl.group(ns='deeper'):
            sl.node('tuilaunch_demos', 'talker', name='deep')
    with sl.group(ns='last_ns', when=When(other, OnProcessExit, sl.arg('delay'))):
        sl.node('tuilaunch_demos', 'talker', name='last')
        with sl.group(when=When(delay=2.)):
            sl.node('tuilaunch_demos', 'talker', name='later')
""", HEADER))
    plan = plan_of(path, delay="2.5")
    main, other, deep, last, later = plan.processes
    assert main.trigger is None
    assert other.trigger is not None and other.trigger.to_json() == {
        "on": "start", "target": main.id, "delay": 1.0}
    assert deep.trigger is other.trigger  # a group inside a when= group waits for that event
    assert deep.full_name == "/deeper/deep"
    assert last.trigger is not None and last.trigger.on == "exit"
    assert last.trigger.target == other.id and last.trigger.delay == 2.5
    assert later.trigger is not None and later.trigger.to_json() == {
        "on": "timer", "target": None, "delay": 2.0, "after": last.trigger.to_json()}


def test_on_process_io_group_collects_callbacks(write):
    path = write(HEADER + """
from launch.actions import LogInfo
def generate_launch_description():
    sl = SimpleLauncher()
    node = sl.node('tuilaunch_demos', 'talker', name='chatty')
    with sl.group(when=When(node, OnProcessIO, io='stdout')):
        sl.add_action(lambda event: LogInfo(msg='said ' + event.text.decode()))
        sl.add_action(lambda event: sl.log_info('again ' + event.text.decode()))
    return sl.launch_description()
""")
    plan = plan_of(path)
    (callbacks,) = plan.actions
    assert callbacks.kind == "event_callback" and callbacks.data == 2
    assert callbacks.trigger is not None and callbacks.trigger.to_json() == {
        "on": "io", "target": "chatty-1", "delay": 0.0, "io": "stdout"}


def test_when_on_process_io_needs_the_stream(write):
    path = write(sl_file("""
    node = sl.node('tuilaunch_demos', 'talker')
    When(node, OnProcessIO)
""", HEADER))
    from tuilaunch.engine import load_file

    with pytest.raises(DslError, match="io='stdout'"):
        load_file(str(path))
