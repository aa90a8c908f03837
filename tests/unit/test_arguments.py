"""Launch arguments: raw Python defaults, arg_map, choices, opaque functions, py_eval."""

from __future__ import annotations

import pytest

from tuilaunch.engine import ArgumentError, LaunchError

from ..conftest import plan_of, sl_file

HEADER = "from simple_launch import SimpleLauncher\n"


def test_raw_defaults_are_typed_and_described(write):
    path = write(sl_file("""
    sl.declare_arg('flag', True, description='a switch')
    sl.declare_arg('count', 3)
    sl.declare_arg('gain', 0.5)
    sl.declare_arg('color', [255, 0, 0])
    sl.declare_arg('mode', 'a', choices=['a', 'b'])
"""))
    args = {a.name: a for a in plan_of(path, count=4).arguments}
    assert [(a.default, a.type) for a in args.values()] == [
        ("True", "bool"), ("3", "int"), ("0.5", "float"), ("[255, 0, 0]", "list"), ("a", "str")]
    assert args["flag"].description == "a switch" and args["mode"].choices == ["a", "b"]
    assert args["count"].value == "4" and args["gain"].value == "0.5"


def test_list_default_round_trips_through_py_eval_and_opaque_function(write):
    substitution = write(sl_file("""
    sl.declare_arg('color', [255, 0, 0])
    rgb = sl.py_eval("' '.join(str(c/255) for c in ", sl.arg('color'), ')')
    sl.node('tuilaunch_demos', 'talker', parameters={'message': rgb})
"""), "subst.py")
    opaque = write(HEADER + """
sl = SimpleLauncher()
sl.declare_arg('color', [255, 0, 0])
def setup():
    color = sl.arg('color')
    assert isinstance(color, list), color
    message = ' '.join(str(c/255) for c in color)
    sl.node('tuilaunch_demos', 'talker', parameters={'message': message})
    return sl.launch_description()
generate_launch_description = sl.launch_description(opaque_function=setup)
""", "opaque.py")
    expected = "1.0 0.0 0.0"
    assert plan_of(substitution).processes[0].parameters["message"] == expected
    assert plan_of(opaque).processes[0].parameters["message"] == expected
    assert plan_of(opaque, color="[0, 255, 0]").processes[0].parameters["message"] == \
        "0.0 1.0 0.0"


def test_opaque_function_sees_python_values(write):
    path = write(HEADER + """
sl = SimpleLauncher()
sl.declare_arg('flag', True)
sl.declare_arg('count', 2)
sl.declare_arg('gain', 0.5)
sl.declare_arg('name', 'bob')
def setup():
    seen = {k: sl.arg(k) for k in ('flag', 'count', 'gain', 'name')}
    sl.log_info(repr(sorted((k, type(v).__name__, v) for k, v in seen.items())))
    for i in range(sl.arg('count')):
        sl.node('tuilaunch_demos', 'talker', name=f'{sl.arg("name")}{i}')
    return sl.launch_description()
generate_launch_description = sl.launch_description(opaque_function=setup)
""")
    plan = plan_of(path, flag="false", count="3")
    assert plan.actions[0].data == repr(sorted([
        ("flag", "bool", False), ("count", "int", 3), ("gain", "float", 0.5),
        ("name", "str", "bob")]))
    assert [p.name for p in plan.processes] == ["bob0", "bob1", "bob2"]


def test_arg_map_accepts_names_and_a_tuple(write):
    path = write(sl_file("""
    sl.declare_arg('a', 'x')
    sl.declare_arg('b', 'y')
    m1 = sl.arg_map('a', 'b')
    m2 = sl.arg_map(('a', 'b'))
    assert list(m1) == list(m2) == ['a', 'b']
    sl.node('tuilaunch_demos', 'talker', parameters=m1)
"""))
    assert plan_of(path, b="z").processes[0].parameters == {"a": "x", "b": "z"}


def test_py_eval_tolerates_lowercase_booleans(write):
    path = write(sl_file("""
    c1 = sl.declare_arg('c1', True)
    c2 = sl.declare_arg('c2', False)
    with sl.group(if_condition=sl.py_eval(c1, ' and not ', c2)):
        sl.node('tuilaunch_demos', 'talker')
"""))
    assert plan_of(path, c1="true", c2="false").processes[0].enabled
    assert not plan_of(path, c1="true", c2="true").processes[0].enabled


def test_value_outside_choices_is_refused_with_the_choices(write):
    path = write(sl_file("""
    sl.declare_arg('mode', 'idle', choices=['idle', 'patrol'])
"""))
    with pytest.raises(ArgumentError) as info:
        plan_of(path, mode="fly")
    text = str(info.value)
    assert "'mode' = 'fly'" in text and "idle, patrol" in text and f"{path}:5" in text


def test_non_boolean_condition_names_the_argument(write):
    path = write(sl_file("""
    sl.declare_arg('robot1', False)
    with sl.group(if_arg='robot1'):
        sl.node('tuilaunch_demos', 'talker')
"""))
    with pytest.raises(ArgumentError) as info:
        plan_of(path, robot1="maybe")
    assert "argument 'robot1' = 'maybe'" in str(info.value)
    assert "robot1:=true" in str(info.value) and f"{path}:6" in str(info.value)


def test_undeclared_command_line_argument_is_a_warning(write):
    path = write(sl_file("""
    sl.declare_arg('robot', 'r1')
"""))
    (warning,) = plan_of(path, robto="r2").warnings
    assert "'robto'" in warning and "robot" in warning


def test_argument_used_but_never_declared(write):
    path = write(sl_file("""
    sl.node('tuilaunch_demos', 'talker', name=sl.arg('ghost'))
"""))
    with pytest.raises(LaunchError, match="'ghost' is used but has no value"):
        plan_of(path)


def test_a_command_line_value_unlike_its_defaults_type_is_a_plan_warning(write):
    """Said wherever the plan's warnings are (start, --print, the TUI), by the function
    the Args tab asks of an edit (type_notes); passed as written, never refused."""
    path = write(sl_file("""
    sl.declare_arg('gain', 1.5)
    sl.declare_arg('count', 3)
    sl.declare_arg('name', 'r1')
"""))
    plan = plan_of(path, gain="abc", count="2.5", name="7")
    assert plan.warnings == [
        "argument 'gain' = 'abc' is not a number like its default 1.5 (passed as written)",
        "argument 'count' = '2.5' is not a whole number like its default 3 (passed as "
        "written)"]
    assert {a.name: a.value for a in plan.arguments}["gain"] == "abc"
    assert plan_of(path, gain="2", count=" 4").warnings == []
