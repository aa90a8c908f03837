"""`sl.include`: package search, arguments, and whether they leak into the includer."""

from __future__ import annotations

import pytest

from tuilaunch.engine import PackageError

from ..conftest import plan_of, run_cli, sl_file

HEADER = "from simple_launch import SimpleLauncher\n"

CHILD = sl_file("""
    sl.declare_arg('robot', 'child_default')
    sl.node('tuilaunch_demos', 'talker', name=sl.arg('robot'))
""")


def parent_text(scope: bool, args: str) -> str:
    return HEADER + f"""
import os
def generate_launch_description():
    sl = SimpleLauncher(scope_included_files={scope})
    sl.declare_arg('robot', 'parent')
    sl.include(None, os.path.join(os.path.dirname(__file__), 'child.py'), launch_arguments={args})
    sl.node('tuilaunch_demos', 'listener', name=sl.arg('robot'))
    return sl.launch_description()
"""


@pytest.mark.parametrize("args", ["{'robot': 'inc'}", "[('robot', 'inc')]"])
def test_include_arguments_leak_into_the_includer_unless_scoped(write, args):
    write(CHILD, "child.py")
    leaky = plan_of(write(parent_text(False, args), "leaky.py"))
    assert [p.name for p in leaky.processes] == ["inc", "inc"]  # launch's default behaviour
    scoped = plan_of(write(parent_text(True, args), "scoped.py"))
    assert [p.name for p in scoped.processes] == ["inc", "parent"]


def test_included_file_sees_command_line_value_when_not_passed(write):
    write(CHILD, "child.py")
    plan = plan_of(write(parent_text(False, "None"), "p.py"), robot="cli")
    assert [p.name for p in plan.processes] == ["cli", "cli"]
    assert [a.name for a in plan.arguments] == ["robot"]


def test_include_from_package_share_with_and_without_launch_dir(write):
    path = write(sl_file("""
    with sl.group(ns='a'):
        sl.include('tuilaunch_demos', 'monitor.launch.py', launch_arguments={'topic': 'x'})
    with sl.group(ns='b'):
        sl.include('tuilaunch_demos', 'monitor.launch.py', 'launch')
"""))
    a, b = plan_of(path).processes
    assert (a.full_name, a.remappings) == ("/a/monitor", [["chatter", "x"]])
    assert (b.full_name, b.remappings) == ("/b/monitor", [["chatter", "/chatter"]])
    assert [arg.name for arg in plan_of(path).arguments] == ["topic"]


def test_include_of_unknown_package_or_file_names_it(write):
    path = write(sl_file("""
    sl.include('no_such_pkg', 'x.launch.py')
"""))
    with pytest.raises(PackageError) as info:
        plan_of(path)
    assert "package 'no_such_pkg' not found" in str(info.value) and f"{path}:5" in str(info.value)
    missing = write(sl_file("""
    sl.include('tuilaunch_demos', 'nope.launch.py')
"""), "missing.py")
    with pytest.raises(PackageError, match=r"'nope\.launch\.py' not found in the share of "
                       r"package 'tuilaunch_demos'"):
        plan_of(missing)


def test_disabled_include_of_a_missing_package_is_not_an_error(write):
    path = write(sl_file("""
    sl.declare_arg('sim', False)
    with sl.group(if_arg='sim'):
        sl.include('gazebo_not_installed', 'sim.launch.py')
    sl.node('tuilaunch_demos', 'talker')
"""))
    plan = plan_of(path)
    assert [p.enabled for p in plan.processes] == [True]
    with pytest.raises(PackageError, match="gazebo_not_installed"):
        plan_of(path, sim="true")


TWICE = HEADER + """
import os
def generate_launch_description():
    sl = SimpleLauncher(scope_included_files=True)
    child = os.path.join(os.path.dirname(__file__), 'child.py')
    sl.include(None, child, launch_arguments={'robot': 'r1'})
    sl.include(None, child, launch_arguments={'robot': 'r2'})
    return sl.launch_description()
"""


def test_a_file_included_twice_shows_each_value_of_its_argument(write):
    write(CHILD, "child.py")
    path = write(TWICE, "twice.py")
    plan = plan_of(path)
    assert [p.name for p in plan.processes] == ["r1", "r2"]
    robot = next(a for a in plan.arguments if a.name == "robot")
    # one row per name in the form; the second include's value is shown beside it
    assert robot.value == "r1"
    assert robot.elsewhere == ["'r2' in child.py:5"]
    assert plan.to_json()["arguments"][0]["elsewhere"] == ["'r2' in child.py:5"]
    shown = run_cli(str(path), "--show-args")
    assert "declared again with 'r2' in child.py:5" in shown.stdout
