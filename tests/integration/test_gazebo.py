"""simple_launch's Gazebo API: what each helper starts, as plans and as headless runs.

Gazebo is not installable here: ros_gz_sim, ros_gz_bridge, ros_gz_image, tf2_ros and `gz` are
FAKE probes in a test ament prefix (tests/integration/fake_prefix.py), and ros_gz_sim's
gz_sim.launch.py
is a stand-in of our own writing.
"""

from __future__ import annotations

import json
import shlex
import sys
from pathlib import Path

import pytest
import yaml

from tuilaunch.engine.describe.python.gazebo import gazebo_message, reset_world_name

from ..conftest import plan_of, run_cli, sl_file
from .fake_prefix import make_prefix, prefix_env, probe_records

WORLD_SDF = """<?xml version="1.0"?>
<sdf version="1.9">
  <world name="shapes">
    <gravity>0 0 -9.8</gravity>
  </world>
</sdf>
"""


@pytest.fixture
def gz(tmp_path, monkeypatch):
    """The fake prefix in this process's environment; no GZ_VERSION; a fresh world name."""
    prefix = make_prefix(tmp_path)
    for name, value in prefix_env(prefix, tmp_path / "probes").items():
        monkeypatch.setenv(name, value)
    monkeypatch.delenv("GZ_VERSION", raising=False)
    monkeypatch.delenv("IGN_VERSION", raising=False)
    monkeypatch.setattr(sys, "argv", ["tuilaunch"])
    reset_world_name()
    yield prefix
    reset_world_name()


@pytest.fixture
def world(tmp_path) -> Path:
    path = tmp_path / "shapes.sdf"
    path.write_text(WORLD_SDF)
    return path


def by_exe(plan, executable):
    found = [p for p in plan.processes if p.executable == executable]
    assert found, f"no {executable} in {[p.executable for p in plan.processes]}"
    return found


def node_arguments(proc):
    """A node's own arguments: its argv between the executable and --ros-args."""
    end = proc.cmd.index("--ros-args") if "--ros-args" in proc.cmd else len(proc.cmd)
    return proc.cmd[1:end]


GAZEBO_HEADER = "from simple_launch import SimpleLauncher, GazeboBridge\n"


def bridge_config(plan, name="gz_bridge"):
    """The YAML the config process writes, read back from its shell command."""
    config = next(p for p in plan.processes if p.name == f"{name}_config")
    assert config.cmd[:2] == ["/bin/sh", "-c"]
    words = shlex.split(config.cmd[2])
    assert words[0] == "echo" and words[2] == ">"
    bridge = next(p for p in plan.processes if p.name == name)
    assert bridge.parameters["config_file"] == words[3]
    return yaml.safe_load(words[1])


def test_gz_launch_includes_gz_sim_with_world_and_arguments(write, gz, world):
    path = write(f"""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher(use_sim_time=True)
    sl.gz_launch('{world}', '-r')
    sl.create_gz_clock_bridge()
    return sl.launch_description()
""")
    plan = plan_of(path)
    sim = [p for p in by_exe(plan, "/bin/sh") if p.cmd[2].startswith("gz ")]
    assert [p.cmd for p in sim] == [["/bin/sh", "-c", f"gz sim {world} -r --force-version 8"]]
    args = {a.name: a.value for a in plan.arguments}
    assert args["gz_args"] == f"{world} -r" and args["use_sim_time"] == "True"
    clock = [p for p in plan.processes if p.name == "gz_clock_bridge"]
    assert clock[0].package == "ros_gz_bridge" and clock[0].executable == "parameter_bridge"
    assert clock[0].parameters["use_sim_time"] is True
    assert bridge_config(plan, "gz_clock_bridge") == [{
        "gz_topic_name": "/clock", "gz_type_name": "gz.msgs.Clock", "ros_topic_name": "/clock",
        "ros_type_name": "rosgraph_msgs/msg/Clock", "direction": "GZ_TO_ROS"}]


def test_world_name_from_the_sdf_reaches_model_topics_and_world_tf(write, gz, world):
    path = write(f"""
from simple_launch import SimpleLauncher, GazeboBridge
def generate_launch_description():
    sl = SimpleLauncher()
    sl.gz_launch('-r {world}')
    with sl.group(ns='r1'):
        sl.create_gz_bridge([GazeboBridge.joint_states_bridge('r1'),
                             GazeboBridge(GazeboBridge.model_prefix('r1') + '/odometry',
                                          'odom', 'nav_msgs/Odometry', GazeboBridge.gz2ros)])
    sl.gz_world_tf()
    return sl.launch_description()
""")
    plan = plan_of(path)
    config = bridge_config(plan)
    assert [(c["gz_topic_name"], c["ros_topic_name"], c["gz_type_name"]) for c in config] == [
        ("/world/shapes/model/r1/joint_state", "joint_states", "gz.msgs.Model"),
        ("/world/shapes/model/r1/odometry", "odom", "gz.msgs.OdometryWithCovariance")]
    bridge = next(p for p in plan.processes if p.name == "gz_bridge")
    assert bridge.full_name == "/r1/gz_bridge"
    tf = next(p for p in plan.processes if p.name == "gz_world_tf")
    assert (tf.package, tf.executable, tf.namespace) == ("tf2_ros", "static_transform_publisher",
                                                        "/")
    assert tf.cmd[1:5] == ["--frame-id", "world", "--child-frame-id", "shapes"]


def test_world_tf_is_skipped_for_a_world_named_world_and_takes_an_explicit_frame(write, gz):
    path = write(sl_file("""
    GazeboBridge.set_world_name('world')
    sl.gz_world_tf()
    with sl.group(ns='explicit'):
        sl.gz_world_tf(sl.declare_arg('frame', 'map'))
""", GAZEBO_HEADER))
    plan = plan_of(path, frame="arena")
    assert [(p.full_name, p.cmd[4]) for p in plan.processes] == [
        ("/explicit/gz_world_tf", "arena")]


def test_spawn_from_topic_with_declared_axes_and_from_file(write, gz):
    path = write(sl_file("""
    sl.declare_gazebo_axes()
    robot = sl.declare_arg('robot', 'r1')
    with sl.group(ns=robot):
        sl.spawn_gz_model(robot, spawn_args=sl.gazebo_axes_args())
    sl.spawn_gz_model('box', model_file='/models/box.sdf', spawn_args=['-z', '2'])
"""))
    plan = plan_of(path, robot="bot", x=1, yaw=1.57)
    names = [a.name for a in plan.arguments]
    assert names[:6] == ["x", "y", "z", "yaw", "pitch", "roll"]
    assert [a.default for a in plan.arguments[:6]] == ["0.0"] * 6
    topic, from_file = by_exe(plan, "create")
    assert topic.package == "ros_gz_sim" and topic.namespace == "/bot"
    assert node_arguments(topic) == [
        "-x", "1", "-y", "0.0", "-z", "0.0", "-R", "0.0", "-P", "0.0", "-Y", "1.57",
        "-topic", "robot_description", "-name", "bot"]
    assert node_arguments(from_file) == [
        "-z", "2", "-file", "/models/box.sdf", "-name", "box"]


def test_only_the_axes_given_are_declared_with_their_defaults(write, gz):
    path = write(sl_file("""
    sl.declare_gazebo_axes(yaw=3.14, z=0.5, elevation=2)
    sl.spawn_gz_model('m', spawn_args=sl.gazebo_axes_args())
"""))
    plan = plan_of(path)
    assert [(a.name, a.default) for a in plan.arguments] == [("yaw", "3.14"), ("z", "0.5")]
    create = by_exe(plan, "create")[0]
    assert create.cmd[1:5] == ["-z", "0.5", "-Y", "3.14"]


def test_gz_axes_args_are_python_strings_inside_an_opaque_function(write, gz):
    path = write("""
from simple_launch import SimpleLauncher
sl = SimpleLauncher()
sl.declare_gazebo_axes(x=1, yaw=0)
def setup():
    args = sl.gazebo_axes_args()
    assert args == ['-x', '2', '-Y', '0'], args
    sl.spawn_gz_model('m', spawn_args=args)
    return sl.launch_description()
generate_launch_description = sl.launch_description(opaque_function=setup)
""")
    assert by_exe(plan_of(path, x=2), "create")[0].cmd[1:5] == ["-x", "2", "-Y", "0"]


def test_bridge_directions_message_types_and_lazy_tuples(write, gz):
    path = write(sl_file("""
    robot = sl.declare_arg('robot', 'r1')
    sl.create_gz_bridge([
        GazeboBridge('/model'/robot/'/pose', 'pose_gt', 'geometry_msgs/Pose',
                     GazeboBridge.gz2ros),
        GazeboBridge(gz_topic=GazeboBridge.model_topic(robot, 'cmd_vel'), ros_topic='cmd_vel',
                     msg='geometry_msgs/msg/Twist', direction=GazeboBridge.ros2gz),
        ('/chatter', 'chatter', 'std_msgs/String', GazeboBridge.bidirectional),
        GazeboBridge('/custom', 'custom', 'my_msgs/Thing', GazeboBridge.gz2ros,
                     'gz.msgs.Thing'),
    ], 'bridge')
""", GAZEBO_HEADER))
    config = bridge_config(plan_of(path, robot="bot"), "bridge")
    assert config == [
        {"gz_topic_name": "/model/bot//pose", "gz_type_name": "gz.msgs.Pose",
         "ros_topic_name": "pose_gt", "ros_type_name": "geometry_msgs/msg/Pose",
         "direction": "GZ_TO_ROS"},
        {"gz_topic_name": "/model/bot/cmd_vel", "gz_type_name": "gz.msgs.Twist",
         "ros_topic_name": "cmd_vel", "ros_type_name": "geometry_msgs/msg/Twist",
         "direction": "ROS_TO_GZ"},
        {"gz_topic_name": "/chatter", "gz_type_name": "gz.msgs.StringMsg",
         "ros_topic_name": "chatter", "ros_type_name": "std_msgs/msg/String",
         "direction": "BIDIRECTIONAL"},
        {"gz_topic_name": "/custom", "gz_type_name": "gz.msgs.Thing",
         "ros_topic_name": "custom", "ros_type_name": "my_msgs/msg/Thing",
         "direction": "GZ_TO_ROS"}]


def test_a_changed_bridge_set_gets_a_new_config_file(write, gz):
    path = write(sl_file("""
    robot = sl.declare_arg('robot', 'r1')
    sl.create_gz_bridge(GazeboBridge('/model'/robot/'pose', 'pose', 'geometry_msgs/Pose',
                                     GazeboBridge.gz2ros))
""", GAZEBO_HEADER))

    def config_file(robot: str) -> str:
        plan = plan_of(path, robot=robot)
        return next(p for p in plan.processes if p.name == "gz_bridge").parameters["config_file"]

    assert config_file("a") == config_file("a") != config_file("b")


def test_image_bridges_use_ros_gz_image_and_add_camera_info(write, gz):
    path = write(sl_file("""
    robot = sl.declare_arg('robot', 'turret')
    sl.create_gz_bridge([
        GazeboBridge(robot + '/image', 'image', 'sensor_msgs/Image', GazeboBridge.gz2ros),
        GazeboBridge('/depth', 'depth', 'sensor_msgs/Image', GazeboBridge.gz2ros),
    ], name='cam')
""", GAZEBO_HEADER))
    plan = plan_of(path)
    image = next(p for p in plan.processes if p.name == "cam_image")
    assert (image.package, image.executable) == ("ros_gz_image", "image_bridge")
    assert image.cmd[1:3] == ["turret/image", "/depth"]
    assert image.remappings == [
        ["turret/image", "image"], ["turret/image/compressed", "image/compressed"],
        ["turret/image/compressedDepth", "image/compressedDepth"],
        ["turret/image/theora", "image/theora"],
        ["/depth", "depth"], ["/depth/compressed", "depth/compressed"],
        ["/depth/compressedDepth", "depth/compressedDepth"], ["/depth/theora", "depth/theora"]]
    # only names whose last plain part says "image" get a camera_info beside them
    assert bridge_config(plan, "cam") == [{
        "gz_topic_name": "turret/camera_info", "gz_type_name": "gz.msgs.CameraInfo",
        "ros_topic_name": "camera_info", "ros_type_name": "sensor_msgs/msg/CameraInfo",
        "direction": "GZ_TO_ROS"}]


def test_ignition_names_when_gz_version_says_fortress(write, gz, monkeypatch, world):
    monkeypatch.setenv("GZ_VERSION", "fortress")
    path = write(f"""
from simple_launch import SimpleLauncher, GazeboBridge
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('sim', False)
    sl.spawn_gz_model('m')
    sl.create_gz_bridge([GazeboBridge.clock(),
                         GazeboBridge('/cam', 'image', 'sensor_msgs/Image', GazeboBridge.gz2ros)])
    with sl.group(if_arg='sim'):
        sl.gz_launch('{world}')
    return sl.launch_description()
""")
    plan = plan_of(path)
    packages = {(p.package, p.executable) for p in plan.processes if p.package}
    assert packages == {("ros_ign_gazebo", "create"), ("ros_ign_bridge", "parameter_bridge"),
                        ("ros_ign_image", "image_bridge")}
    assert bridge_config(plan) == [{
        "ign_topic_name": "/clock", "ign_type_name": "ignition.msgs.Clock",
        "ros_topic_name": "/clock", "ros_type_name": "rosgraph_msgs/msg/Clock",
        "direction": "IGN_TO_ROS"}]
    skipped = json.dumps(plan.tree.to_json())
    assert "ros_ign_gazebo/launch/ign_gazebo.launch.py" in skipped
    # not installed here: each names its package, the others still plan
    assert all("not found" in (p.error or "") for p in plan.processes if p.package)


def test_save_gz_world_runs_generate_gz_world_after_the_delay(write, gz, world, tmp_path):
    saved = tmp_path / "full.sdf"
    path = write(f"""
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher()
    sl.gz_launch('{world}', full_world='{saved}', save_after=2.5)
    sl.save_gz_world('/tmp/other.sdf')
    return sl.launch_description()
""")
    plan = plan_of(path)
    first, second = by_exe(plan, "generate_gz_world")
    assert first.package == "simple_launch"
    assert (first.cmd[1], first.trigger.on, first.trigger.delay) == (str(saved), "timer", 2.5)
    assert (second.cmd[1], second.trigger.delay) == ("/tmp/other.sdf", 5.0)
    assert plan.arguments[0].value == str(world)
    # once saved, the full world is what Gazebo loads, and nothing saves it again
    saved.write_text(WORLD_SDF)
    plan = plan_of(path)
    assert len(by_exe(plan, "generate_gz_world")) == 1
    assert next(a for a in plan.arguments if a.name == "gz_args").value == str(saved)


def test_readme_conditional_gazebo_bridge_example(write, gz):
    path = write("""
from simple_launch import SimpleLauncher, GazeboBridge
def generate_launch_description():
    sl = SimpleLauncher(use_sim_time=False)
    sl.declare_arg('robot', default_value = 'robot1')
    robot = sl.arg('robot')
    GazeboBridge.set_world_name('arena')
    with sl.group(ns = robot):
        with sl.group(if_condition = sl.sim_time):
            sl.spawn_gz_model(robot)
            gz_js_topic = GazeboBridge.model_prefix(robot)/'joint_state'
            js_bridge = GazeboBridge(gz_topic = gz_js_topic, ros_topic = 'joint_states',
                                     msg = 'sensor_msgs/JointState',
                                     direction = GazeboBridge.gz2ros)
            pose_bridge = GazeboBridge('/model'/robot/'/pose',
                                       'pose_gt', 'geometry_msgs/Pose', GazeboBridge.gz2ros)
            sl.create_gz_bridge([js_bridge, pose_bridge])
    return sl.launch_description()
""")
    assert not any(p.enabled for p in plan_of(path).processes)
    plan = plan_of(path, use_sim_time="true", robot="r2")
    assert {p.label for p in plan.processes if p.enabled} == {
        "/r2/<create>", "/r2/gz_bridge", "/r2/gz_bridge_config"}
    assert [c["gz_topic_name"] for c in bridge_config(plan)] == [
        "/world/arena/model/r2/joint_state", "/model/r2//pose"]


def test_gazebo_names_import_from_where_simple_launch_defines_them(write, gz):
    path = write("""
from simple_launch import SimpleLauncher
from simple_launch.gazebo import GazeboBridge, ros_gz_prefix
from simple_launch.simple_substitution import SimpleSubstitution
def generate_launch_description():
    sl = SimpleLauncher()
    assert ros_gz_prefix() == 'gz'
    sl.create_gz_bridge(GazeboBridge(SimpleSubstitution('/a'), 'b', 'std_msgs/Bool',
                                     GazeboBridge.ros2gz))
    return sl.launch_description()
""")
    assert bridge_config(plan_of(path))[0]["gz_type_name"] == "gz.msgs.Boolean"


@pytest.mark.parametrize("line, message", [
    ("GazeboBridge('/a', 'a', 'my_msgs/Unknown', GazeboBridge.gz2ros)",
     "no Gazebo message type is known for my_msgs/msg/Unknown"),
    ("GazeboBridge('/a', 'a', 'std_msgs/Bool', 'both')", "direction 'both' is not one of"),
    ("GazeboBridge.joint_states_bridge('r1')", "the Gazebo world name is unknown"),
])
def test_gazebo_mistakes_name_the_line(write, tmp_path, line, message):
    path = write(f"""
from simple_launch import SimpleLauncher, GazeboBridge
def generate_launch_description():
    sl = SimpleLauncher()
    sl.create_gz_bridge([{line}])
    return sl.launch_description()
""")
    # no `gz` on PATH: asking a running Gazebo for the world fails at once
    env = {"PATH": str(Path(sys.executable).parent) + ":/usr/bin:/bin", "GZ_VERSION": "harmonic"}
    done = run_cli(str(path), "--print", env=env)
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert "test_launch.py:5: " in lines[0], done.stderr
    assert message in lines[0] and "Traceback" not in done.stderr


def test_message_table_follows_ros_gz_bridge():
    assert gazebo_message("sensor_msgs/msg/Imu") == "gz.msgs.IMU"
    assert gazebo_message("tf2_msgs/msg/TFMessage") == "gz.msgs.Pose_V"
    assert gazebo_message("std_msgs/msg/Float64") == "gz.msgs.Double"
    assert gazebo_message("std_msgs/msg/Float128") is None


def test_headless_run_starts_gazebo_spawner_and_bridges_with_their_config(write, tmp_path,
                                                                          world):
    prefix = make_prefix(tmp_path)
    probes = tmp_path / "probes"
    env = prefix_env(prefix, probes)
    env["ROS_LOG_DIR"] = str(tmp_path / "log")
    env["TMPDIR"] = str(tmp_path)  # the bridge configs and parameter files go there
    path = write(f"""
from simple_launch import SimpleLauncher, GazeboBridge
def generate_launch_description():
    sl = SimpleLauncher(use_sim_time=True)
    sl.gz_launch('{world}', '-r -s')
    sl.create_gz_clock_bridge()
    with sl.group(ns='turret'):
        sl.spawn_gz_model('turret', spawn_args=['-x', '1'])
        sl.create_gz_bridge([GazeboBridge.joint_states_bridge('turret'),
                             GazeboBridge('/turret/image', 'image', 'sensor_msgs/Image',
                                          GazeboBridge.gz2ros)])
    return sl.launch_description()
""")
    done = run_cli(str(path), "--headless", env={**env, "GZ_VERSION": "harmonic"})
    assert done.returncode == 0, done.stdout + done.stderr
    records = {}
    for record in probe_records(probes):
        records.setdefault(record["exe"], []).append(record)
    assert records["gz"][0]["argv"] == ["sim", str(world), "-r", "-s", "--force-version", "8"]
    create = records["create"][0]
    assert create["argv"][:7] == ["-x", "1", "-topic", "robot_description", "-name", "turret",
                                  "--ros-args"]
    assert "__ns:=/turret" in " ".join(create["argv"])
    assert create["params"] == {"use_sim_time": True}
    bridges = {r["argv"][r["argv"].index("-r") + 1]: r for r in records["parameter_bridge"]}
    clock = yaml.safe_load(bridges["__node:=gz_clock_bridge"]["config"])
    assert clock[0]["gz_topic_name"] == "/clock"
    turret = yaml.safe_load(bridges["__node:=gz_bridge"]["config"])
    assert [(c["gz_topic_name"], c["ros_topic_name"]) for c in turret] == [
        ("/world/shapes/model/turret/joint_state", "joint_states"),
        ("/turret/camera_info", "camera_info")]
    assert len(list(tmp_path.glob("tuilaunch-gz*.yaml"))) == 2
    image = records["image_bridge"][0]["argv"]
    assert image[0] == "/turret/image"
    assert "/turret/image:=image" in image and "__node:=gz_bridge_image" in " ".join(image)


def test_spawn_args_may_be_a_string_or_nested_lists(write, gz):
    path = write(sl_file("""
    sl.declare_gazebo_axes(x=1.0, y=2.0)
    sl.spawn_gz_model('a', spawn_args='-z 0.3 -Y 1')
    sl.spawn_gz_model('b', spawn_args=[sl.gazebo_axes_args(), ['-z', '0.1']])
"""))
    a, b = by_exe(plan_of(path), "create")
    assert node_arguments(a) == ["-z", "0.3", "-Y", "1", "-topic", "robot_description",
                                 "-name", "a"]
    assert node_arguments(b) == ["-x", "1.0", "-y", "2.0", "-z", "0.1", "-topic",
                                 "robot_description", "-name", "b"]


@pytest.mark.parametrize("answer, world", [
    ("Requesting state for world [arena]...", "arena"),
    ("Service call timed out for [/world/state]", None),
])
def test_world_name_asked_from_a_running_gazebo(write, tmp_path, answer, world):
    # FAKE `gz`: answers `gz model --list` as a running (or absent) Gazebo would
    fake_bin = tmp_path / "bin"
    fake_bin.mkdir()
    gz_script = fake_bin / "gz"
    gz_script.write_text(f"#!/bin/sh\n[ \"$1 $2\" = 'model --list' ] && echo '{answer}'\n")
    gz_script.chmod(0o755)
    path = write(sl_file("""
    sl.log_info('world is ' + GazeboBridge.world())
""", GAZEBO_HEADER))
    env = {"PATH": f"{fake_bin}:{Path(sys.executable).parent}:/usr/bin:/bin",
           "GZ_VERSION": "harmonic"}
    done = run_cli(str(path), "--print", "--json", env=env)
    if world is None:
        assert "test_launch.py:5: GazeboBridge.world(): the Gazebo world name is unknown" \
            in done.stderr
    else:
        assert done.returncode == 0, done.stderr
        actions = json.loads(done.stdout)["actions"]
        assert actions[0]["data"] == f"world is {world}"


def test_gz_launch_says_which_world_file_it_found(write, gz, world):
    path = write(f"""
from simple_launch import SimpleLauncher

def generate_launch_description():
    sl = SimpleLauncher()
    sl.gz_launch({str(world)!r}, '-r')
    sl.gz_launch('nowhere.sdf')
    return sl.launch_description()
""")
    done = run_cli(str(path), "--print")
    lines = done.stdout.splitlines()
    # as simple_launch's console.info / console.warn print them
    assert f'\x1b[92m[simple_launch]: Gazebo world "shapes" found @ {world}\x1b[0m' in lines, \
        done.stdout + done.stderr
    assert '\x1b[93m[simple_launch]: Could not read Gazebo world @ "nowhere.sdf"\x1b[0m' \
        in lines
