"""`sl.find` / `sl.include` search a package share as simple_launch does, and xacro arguments
reach xacro as simple_launch's `xacro FILE name:=value` command line gives them."""

from __future__ import annotations

import pytest

from tuilaunch.engine.errors import LaunchError

from ..conftest import plan_of, run_cli
from .fake_prefix import make_prefix, prefix_env

# One file name at three depths of a (fake) package share, and an included launch file at two.
SHARE = {
    "demo_pkg/robot.yaml": "depth: 0\n",
    "demo_pkg/config/robot.yaml": "depth: 1\n",
    "demo_pkg/config/deep/robot.yaml": "depth: 2\n",
    "demo_pkg/part.launch.py": "raise RuntimeError('the shallow copy was included')\n",
    "demo_pkg/launch/sub/part.launch.py": """
        from simple_launch import SimpleLauncher
        def generate_launch_description():
            sl = SimpleLauncher()
            sl.node('demo_pkg', 'probe', name='from_deep_include')
            return sl.launch_description()
        """,
    "demo_pkg/urdf/bot.xacro": """<?xml version="1.0"?>
        <robot name="bot" xmlns:xacro="http://www.ros.org/wiki/xacro">
          <xacro:arg name="rgb" default="1 1 1"/>
          <xacro:arg name="prefix" default=""/>
          <link name="$(arg prefix)base">
            <visual><material name="m"><color rgba="$(arg rgb) 1"/></material></visual>
          </link>
        </robot>
        """,
}


@pytest.fixture
def demo(tmp_path, monkeypatch):
    prefix = make_prefix(tmp_path, {"demo_pkg": ["probe"]}, SHARE)
    for name, value in prefix_env(prefix, tmp_path / "probes").items():
        monkeypatch.setenv(name, value)
    return prefix / "share" / "demo_pkg"


def test_find_takes_the_deepest_match_first(write, demo):
    path = write("""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    name = sl.declare_arg('name', 'robot')
    sl.node('demo_pkg', 'probe', parameters={
        'eager': sl.find('demo_pkg', 'robot.yaml'),
        'lazy': sl.find('demo_pkg', name + '.yaml'),
        'in_dir': sl.find('demo_pkg', 'robot.yaml', 'config'),
    })
    return sl.launch_description()
""")
    params = plan_of(path).processes[0].parameters
    assert params == {"eager": str(demo / "config" / "deep" / "robot.yaml"),
                      "lazy": str(demo / "config" / "deep" / "robot.yaml"),
                      "in_dir": str(demo / "config" / "robot.yaml")}


def test_include_finds_the_deepest_launch_file(write, demo):
    path = write("""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    sl.include('demo_pkg', 'part.launch.py')
    return sl.launch_description()
""")
    assert [p.name for p in plan_of(path).processes] == ["from_deep_include"]


def test_find_of_a_missing_file_names_package_and_share(write, demo):
    path = write("""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    sl.node('demo_pkg', 'probe', parameters=[sl.find('demo_pkg', 'nope.yaml')])
    return sl.launch_description()
""")
    done = run_cli(str(path), "--print", env={k: v for k, v in prefix_env(
        demo.parent.parent, demo.parent.parent / "probes").items()})
    first = done.stderr.splitlines()[0]
    assert "test_launch.py:5: file 'nope.yaml' not found in the share of package 'demo_pkg'" \
        in first and "Traceback" not in done.stderr


def test_quoted_xacro_values_lose_their_shell_quotes(write, demo):
    # map_simulator builds "'0.0 1.0 0.0'" so that the xacro command line keeps one value
    path = write("""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('color', [0, 255, 0])
    rgb = sl.name_join("'", sl.py_eval("' '.join(str(c/255) for c in ", sl.arg('color'), ')'),
                       "'")
    sl.robot_state_publisher('demo_pkg', 'bot.xacro',
                             xacro_args={'prefix': 'r1/', 'rgb': rgb})
    return sl.launch_description()
""")
    description = plan_of(path).processes[0].parameters["robot_description"]
    assert 'rgba="0.0 1.0 0.0 1"' in description
    assert 'name="r1/base"' in description
    assert "'" not in description.split("<robot", 1)[1]


def test_xacro_quotes_also_apply_inside_an_opaque_function(write, demo):
    path = write("""
from simple_launch import SimpleLauncher
sl = SimpleLauncher()
def setup():
    sl.robot_state_publisher('demo_pkg', 'bot.xacro', xacro_args={'rgb': '"0 0 1"'})
    return sl.launch_description()
generate_launch_description = sl.launch_description(opaque_function=setup)
""")
    description = plan_of(path).processes[0].parameters["robot_description"]
    assert 'rgba="0 0 1 1"' in description


def test_unquoted_xacro_value_with_spaces_is_one_clear_error(write, demo):
    path = write("""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    sl.robot_state_publisher('demo_pkg', 'bot.xacro', xacro_args={'rgb': '0 1 0'})
    return sl.launch_description()
""")
    with pytest.raises(LaunchError, match=r"xacro argument word '1' is not name:=value") as err:
        plan_of(path)
    assert err.value.origin is not None and err.value.origin.line == 5


def test_namespaced_tf_keeps_tf_inside_the_robot_namespace(write, demo):
    path = write("""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    with sl.group(ns='r1'):
        sl.robot_state_publisher('demo_pkg', 'bot.xacro', namespaced_tf=True,
                                 remappings={'joint_states': 'js'})
    return sl.launch_description()
""")
    proc = plan_of(path).processes[0]
    assert proc.remappings == [["joint_states", "js"], ["/tf", "tf"], ["/tf_static", "tf_static"]]
    assert proc.namespace == "/r1"


def test_removed_prefix_gz_plugins_is_refused_by_name(write, demo):
    path = write("""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    sl.robot_state_publisher('demo_pkg', 'bot.xacro', prefix_gz_plugins=False)
    sl.robot_state_publisher('demo_pkg', 'bot.xacro', prefix_gz_plugins=True)
    return sl.launch_description()
""")
    with pytest.raises(LaunchError, match=r"prefix_gz_plugins=True\) is not supported") as err:
        plan_of(path)
    assert err.value.origin is not None and err.value.origin.line == 6
