"""simple_launch's Gazebo helpers: `gz_launch`, `spawn_gz_model`, `GazeboBridge` and friends.

Each helper builds ordinary entities (an include of ros_gz_sim's `gz_sim.launch.py`, nodes of
`ros_gz_sim`, `ros_gz_bridge`, `ros_gz_image`, `tf2_ros`), so a plan shows exactly which
processes Gazebo support starts. Ignition-era installs (`ros_ign_*`, Fortress) get the `ign`
names, as simple_launch picks them.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from typing import TYPE_CHECKING, Any, Protocol

from ...errors import DslError, Origin, caller_origin
from ...packages import known_packages
from ..entities import ExecuteProcess
from ..substitutions import (
    PerformContext,
    SimpleSubstitution,
    Substitution,
    SubValue,
    flatten,
    perform,
)
from . import console

if TYPE_CHECKING:
    from contextlib import AbstractContextManager

    from ..events import When


class _Launcher(Protocol):
    """What the Gazebo helpers use of SimpleLauncher."""

    gz_axes: tuple[str, ...]

    def declare_arg(self, name: str, default_value: Any = None, description: str | None = None,
                    choices: Any = None, **kwargs: Any) -> Any: ...

    def arg(self, name: str) -> Any: ...

    def node(self, package: SubValue = None, executable: SubValue = None,
             plugin: SubValue = None, **node_args: Any) -> Any: ...

    def include(self, package: SubValue = None, launch_file: SubValue = None,
                launch_dir: SubValue = None, launch_arguments: Any = None) -> Any: ...

    def add_action(self, action: Any) -> Any: ...

    def group(self, ns: SubValue = None, if_arg: Any = None, unless_arg: Any = None,
              if_condition: Any = None, unless_condition: Any = None,
              when: When | None = None) -> AbstractContextManager[Any]: ...

    def save_gz_world(self, dst: SubValue, after: float = 5.0) -> None: ...

    def create_gz_bridge(self, bridges: Any, name: SubValue = "gz_bridge") -> None: ...

GZ_AXES = ("x", "y", "z", "yaw", "pitch", "roll")
# `ros_gz_sim create` takes the angles as -R -P -Y
_SPAWN_FLAGS = (("x", "x"), ("y", "y"), ("z", "z"), ("roll", "R"), ("pitch", "P"), ("yaw", "Y"))
# the image bridge publishes these transports beside the raw topic
_IMAGE_TRANSPORTS = ("", "/compressed", "/compressedDepth", "/theora")

# ROS message -> Gazebo message, as ros_gz_bridge documents its conversions (when a ROS type
# has two Gazebo counterparts, the one simple_launch picks)
_GZ_TYPES: dict[str, dict[str, str]] = {
    "actuator_msgs": {"Actuators": "Actuators"},
    "builtin_interfaces": {"Time": "Time"},
    "geometry_msgs": {
        "Point": "Vector3d", "Vector3": "Vector3d", "Quaternion": "Quaternion",
        "Pose": "Pose", "PoseStamped": "Pose", "Transform": "Pose", "TransformStamped": "Pose",
        "PoseArray": "Pose_V", "PoseWithCovariance": "PoseWithCovariance",
        "PoseWithCovarianceStamped": "PoseWithCovariance", "Twist": "Twist",
        "TwistStamped": "Twist", "TwistWithCovariance": "TwistWithCovariance",
        "TwistWithCovarianceStamped": "TwistWithCovariance", "Wrench": "Wrench",
        "WrenchStamped": "Wrench",
    },
    "gps_msgs": {"GPSFix": "NavSat"},
    "nav_msgs": {"Odometry": "OdometryWithCovariance"},
    "rcl_interfaces": {"ParameterValue": "Any"},
    "ros_gz_interfaces": {
        "Altimeter": "Altimeter", "Contact": "Contact", "Contacts": "Contacts",
        "Dataframe": "Dataframe", "Entity": "Entity", "EntityWrench": "EntityWrench",
        "Float32Array": "Float_V", "GuiCamera": "GUICamera", "JointWrench": "JointWrench",
        "Light": "Light", "ParamVec": "Param", "SensorNoise": "SensorNoise",
        "StringVec": "StringMsg_V", "TrackVisual": "TrackVisual", "VideoRecord": "VideoRecord",
    },
    "rosgraph_msgs": {"Clock": "Clock"},
    "sensor_msgs": {
        "BatteryState": "BatteryState", "CameraInfo": "CameraInfo",
        "FluidPressure": "FluidPressure", "Image": "Image", "Imu": "IMU",
        "JointState": "Model", "Joy": "Joy", "LaserScan": "LaserScan",
        "MagneticField": "Magnetometer", "NavSatFix": "NavSat",
        "PointCloud2": "PointCloudPacked",
    },
    "std_msgs": {
        "Bool": "Boolean", "ColorRGBA": "Color", "Empty": "Empty", "Float32": "Float",
        "Float64": "Double", "Header": "Header", "Int32": "Int32", "String": "StringMsg",
        "UInt32": "UInt32",
    },
    "tf2_msgs": {"TFMessage": "Pose_V"},
    "trajectory_msgs": {"JointTrajectory": "JointTrajectory"},
    "vision_msgs": {"Detection2D": "AnnotatedAxisAligned2DBox",
                    "Detection2DArray": "AnnotatedAxisAligned2DBox_V"},
}


def gazebo_message(ros_msg: str) -> str | None:
    """`gz.msgs.X` for a ROS type `pkg/msg/Type`, or None when the bridge has no conversion."""
    package, _, name = ros_msg.partition("/msg/")
    gz_name = _GZ_TYPES.get(package, {}).get(name)
    return None if gz_name is None else f"gz.msgs.{gz_name}"


def ros_gz_prefix() -> str:
    """'gz' (Garden and later, ROS Humble on) or 'ign' (Fortress and older ROS).

    GZ_VERSION / IGN_VERSION decide first, as in simple_launch; otherwise the installed
    packages do (ros_gz or ros_gz_sim means gz, only ros_ign_gazebo means ign).
    """
    for variable in ("IGN_VERSION", "GZ_VERSION"):
        if variable in os.environ:
            return "ign" if os.environ[variable] == "fortress" else "gz"
    packages = known_packages()
    if "ros_gz" in packages or "ros_gz_sim" in packages:
        return "gz"
    if "ros_ign_gazebo" in packages:
        return "ign"
    return "gz"


def only_show_args() -> bool:
    """True when the launch was asked only to list its arguments (nothing will run)."""
    return any(flag in sys.argv for flag in ("-s", "--show-args", "--show-arguments"))


_WORLD_NAME = re.compile(r"<world\s+name\s*=\s*[\"']([^\"']+)[\"']")


def world_name_in(path: str) -> str | None:
    """The name of the first `<world name="...">` of an SDF file, if it can be read."""
    try:
        with open(path, encoding="utf-8", errors="replace") as handle:
            found = _WORLD_NAME.search(handle.read())
    except OSError:
        return None
    return found.group(1) if found else None


def _world_from_running_gazebo() -> str | None:
    """Asks a running Gazebo (`gz model --list` prints `Requesting state for world [name]`)."""
    candidates = ["gz", "ign"]
    if ros_gz_prefix() == "ign" and "GZ_VERSION" not in os.environ:
        candidates = ["ign", "gz"]
    for executable in candidates:
        try:
            done = subprocess.run([executable, "model", "--list"], capture_output=True,
                                  text=True, timeout=15)
        except (OSError, subprocess.TimeoutExpired):
            continue
        output = done.stdout + done.stderr
        found = re.search(r"\[([^\]]+)\]", output)
        if done.returncode == 0 and found and "timed out" not in output:
            return found.group(1)
    return None


class _ShellQuoted(Substitution):
    """A value performed, then quoted for `sh -c`, so any topic name survives the shell."""

    def __init__(self, value: SubValue) -> None:
        self.value = value

    def perform(self, context: PerformContext) -> str:
        return shlex.quote(perform(self.value, context))

    def describe(self) -> str:
        return "'<bridge YAML>'"


class _BridgeConfigPath(Substitution):
    """Where a bridge's YAML goes: named after its content, so a changed set of bridges is a
    new file (and a restarted bridge), never a file rewritten under a running one."""

    def __init__(self, name: SubValue, content: SubValue) -> None:
        self.name, self.content = name, content

    def perform(self, context: PerformContext) -> str:
        import hashlib  # OpenSSL's libcrypto: megabytes of memory, only for the files that ask
        import tempfile

        name = perform(self.name, context)
        digest = hashlib.sha1(
            (name + "\0" + perform(self.content, context)).encode()).hexdigest()[:12]
        safe = re.sub(r"[^A-Za-z0-9_.-]", "_", name)
        return os.path.join(tempfile.gettempdir(), f"tuilaunch-{safe}-{digest}.yaml")

    def describe(self) -> str:
        return f"$(bridge-config {self.name})"


def _split_tail(value: SimpleSubstitution) -> tuple[list[Any], Any]:
    """The parts of a concatenation before its last plain part, and that last part."""
    parts = list(value.parts)
    if not parts:
        return [], None
    last = parts[-1]
    if isinstance(last, SimpleSubstitution):
        head, tail = _split_tail(last)
        return parts[:-1] + head, tail
    return parts[:-1], last


class GazeboBridge:
    """One topic bridged between Gazebo and ROS, for `SimpleLauncher.create_gz_bridge`."""

    gz2ros = "["
    ros2gz = "]"
    bidirectional = "@"
    _world_name: str | None = None

    def __init__(self, gz_topic: SubValue = None, ros_topic: SubValue = None,
                 ros_msg: str | None = None, direction: str | None = None,
                 gz_msg: str | None = None, *, msg: str | None = None) -> None:
        origin = caller_origin()
        ros_msg = ros_msg if ros_msg is not None else msg
        if gz_topic is None or ros_topic is None or ros_msg is None or direction is None:
            raise DslError("GazeboBridge needs gz_topic, ros_topic, ros_msg and direction",
                           origin, hint="GazeboBridge('/gz/topic', 'ros_topic', "
                           "'std_msgs/msg/Float64', GazeboBridge.gz2ros)")
        if not isinstance(ros_msg, str) or "/" not in ros_msg:
            raise DslError(f"GazeboBridge: ROS message type {ros_msg!r} is not 'package/Type'",
                           origin)
        if "/msg/" not in ros_msg:
            ros_msg = ros_msg.replace("/", "/msg/", 1)
        if direction not in (self.gz2ros, self.ros2gz, self.bidirectional):
            raise DslError(f"GazeboBridge: direction {direction!r} is not one of "
                           "GazeboBridge.gz2ros, ros2gz, bidirectional", origin)
        found = gz_msg if gz_msg is not None else gazebo_message(ros_msg)
        if found is None:
            raise DslError(f"GazeboBridge: no Gazebo message type is known for {ros_msg}",
                           origin, hint="pass gz_msg='gz.msgs.<Type>'")
        self.gz_msg: str = found
        self.ros_msg: str = ros_msg
        self.direction: str = direction
        self.gz_topic = SimpleSubstitution(gz_topic)
        self.ros_topic = SimpleSubstitution(ros_topic)
        # images go through ros_gz_image, whatever the direction
        self.is_image = ros_msg == "sensor_msgs/msg/Image"
        self.origin: Origin | None = origin

    def yaml(self, prefix: str | None = None) -> SimpleSubstitution:
        """This bridge as one entry of a `parameter_bridge` YAML config."""
        gz = prefix or ros_gz_prefix()
        direction = {self.gz2ros: f"{gz.upper()}_TO_ROS",
                     self.ros2gz: f"ROS_TO_{gz.upper()}"}.get(self.direction, "BIDIRECTIONAL")
        gz_msg = self.gz_msg.replace("gz.", "ignition.", 1) if gz == "ign" else self.gz_msg
        return SimpleSubstitution(
            f"- {gz}_topic_name: ", self.gz_topic, "\n",
            f"  {gz}_type_name: ", gz_msg, "\n",
            "  ros_topic_name: ", self.ros_topic, "\n",
            "  ros_type_name: ", self.ros_msg, "\n",
            "  direction: ", direction, "\n")

    @staticmethod
    def valid(direction: str) -> bool:
        return direction in (GazeboBridge.gz2ros, GazeboBridge.ros2gz, GazeboBridge.bidirectional)

    @staticmethod
    def set_world_name(name: str) -> None:
        """The Gazebo world's name, when Gazebo is started elsewhere (no gz_launch here)."""
        GazeboBridge._world_name = name

    @staticmethod
    def world() -> str:
        """The world's name: from gz_launch's SDF, set_world_name, or a running Gazebo."""
        if GazeboBridge._world_name is not None:
            return GazeboBridge._world_name
        if only_show_args():
            GazeboBridge._world_name = "dummy"  # silent afterwards, as simple_launch
            console.warn("This launch file will request information on a running Gazebo "
                         "instance at the time of the launch")
            return "dummy"
        found = _world_from_running_gazebo()
        if found is None:
            raise DslError(
                "GazeboBridge.world(): the Gazebo world name is unknown: no gz_launch() with a "
                "readable world file and no GazeboBridge.set_world_name() came first, and no "
                "running Gazebo answered `gz model --list`", caller_origin(),
                hint="call GazeboBridge.set_world_name('<world>') before using the world name")
        GazeboBridge._world_name = found
        console.info(f'GazeboBridge: found world "{found}"')
        return found

    @staticmethod
    def model_prefix(model: SubValue) -> Any:
        """`/world/<world>/model/<model>`."""
        return f"/world/{GazeboBridge.world()}/model/" + model

    @staticmethod
    def model_topic(model: SubValue, topic: SubValue) -> SimpleSubstitution:
        """`/model/<model>/<topic>`."""
        return SimpleSubstitution("/model/", model, "/", topic)

    @staticmethod
    def clock() -> GazeboBridge:
        return GazeboBridge("/clock", "/clock", "rosgraph_msgs/msg/Clock", GazeboBridge.gz2ros)

    @staticmethod
    def joint_states_bridge(model: SubValue) -> GazeboBridge:
        """Gazebo's joint states of a model onto the (relative) ROS topic `joint_states`."""
        topic = f"/world/{GazeboBridge.world()}/model/" + model + "/joint_state"
        return GazeboBridge(topic, "joint_states", "sensor_msgs/msg/JointState",
                            GazeboBridge.gz2ros)


def reset_world_name() -> None:
    """Forget the world name (it lives as long as the process, as in simple_launch)."""
    GazeboBridge._world_name = None


def _camera_info_bridge(bridge: GazeboBridge) -> GazeboBridge | None:
    """The `camera_info` topic beside an image topic, when both names end in plain text."""
    gz_head, gz_tail = _split_tail(bridge.gz_topic)
    ros_head, ros_tail = _split_tail(bridge.ros_topic)
    if not all(isinstance(t, str) and "image" in t for t in (gz_tail, ros_tail)):
        return None
    gz_info = gz_tail[:gz_tail.rfind("image")] + "camera_info"
    ros_info = ros_tail[:ros_tail.rfind("image")] + "camera_info"
    return GazeboBridge(SimpleSubstitution(gz_head, gz_info),
                        SimpleSubstitution(ros_head, ros_info),
                        "sensor_msgs/msg/CameraInfo", GazeboBridge.gz2ros)


class GazeboLauncher:
    """The Gazebo part of SimpleLauncher (mixed into it)."""

    gz_axes: tuple[str, ...] = GZ_AXES

    def declare_gazebo_axes(self: _Launcher, **axes: Any) -> None:
        """x, y, z, yaw, pitch, roll as launch arguments (default 0), or only those given."""
        if axes:
            self.gz_axes = tuple(a for a in axes if a in self.gz_axes)
            for axis in self.gz_axes:
                self.declare_arg(axis, default_value=axes[axis])
            return
        self.gz_axes = GZ_AXES
        for axis in self.gz_axes:
            self.declare_arg(axis, default_value=0.0)

    def gazebo_axes_args(self: _Launcher) -> list[Any]:
        """The declared axes as `ros_gz_sim create` flags: ['-x', <x>, ..., '-Y', <yaw>]."""
        out: list[Any] = []
        for axis, flag in _SPAWN_FLAGS:
            if axis in self.gz_axes:
                value = self.arg(axis)
                out += ["-" + flag, value if isinstance(value, str | Substitution)
                        else str(value)]
        return out

    def gz_launch(self: _Launcher, world_file: SubValue, gz_args: SubValue = None,
                  full_world: SubValue = None, save_after: float = 5.0) -> Any:
        """Includes ros_gz_sim's gz_sim.launch.py with `gz_args` = world file + arguments."""
        if isinstance(full_world, str):
            if os.path.exists(full_world):
                world_file = full_world
            else:
                self.save_gz_world(full_world, save_after)
        _remember_world(world_file, gz_args)
        if isinstance(world_file, str) and (gz_args is None or isinstance(gz_args, str)):
            all_args: SubValue = world_file if gz_args is None else f"{world_file} {gz_args}"
        else:
            all_args = SimpleSubstitution(world_file, " ", gz_args)
        if ros_gz_prefix() == "gz":
            return self.include("ros_gz_sim", "gz_sim.launch.py", "launch",
                                launch_arguments={"gz_args": all_args})
        return self.include("ros_ign_gazebo", "ign_gazebo.launch.py", "launch",
                            launch_arguments={"ign_args": all_args})

    def save_gz_world(self: _Launcher, dst: SubValue, after: float = 5.0) -> None:
        """Runs simple_launch's `generate_gz_world DST` `after` seconds from the start."""
        from ..events import When

        with self.group(when=When(delay=after)):
            self.node("simple_launch", "generate_gz_world", arguments=[dst])

    def spawn_gz_model(self: _Launcher, name: SubValue, topic: SubValue = "robot_description",
                       model_file: SubValue = None, spawn_args: Any = None,
                       only_new: bool = True) -> Any:
        """`ros_gz_sim create` for a model from a file, or from a (relative) description topic.

        `only_new` is accepted as documented; `create` already refuses a name that exists.
        """
        # a string is split like node arguments; nested lists (axes args) are flattened
        args = spawn_args.split() if isinstance(spawn_args, str) else flatten(spawn_args)
        if model_file is not None:
            args += ["-file", model_file, "-name", name]
        else:
            args += ["-topic", topic, "-name", name]
        package = "ros_gz_sim" if ros_gz_prefix() == "gz" else "ros_ign_gazebo"
        return self.node(package, "create", arguments=args)

    def create_gz_bridge(self: _Launcher, bridges: Any, name: SubValue = "gz_bridge")\
            -> None:
        """A `parameter_bridge` for the bridges (YAML config), an `image_bridge` for images."""
        items = [bridges] if isinstance(bridges, GazeboBridge) else list(bridges or [])
        if not items:
            return
        items = [b if isinstance(b, GazeboBridge) else GazeboBridge(*b) for b in items]
        gz = ros_gz_prefix()
        images = [b for b in items if b.is_image]
        infos = [info for info in map(_camera_info_bridge, images) if info is not None]
        plain = [b for b in items if not b.is_image] + infos
        if plain:
            config = SimpleSubstitution([b.yaml(gz) for b in plain])
            path = _BridgeConfigPath(name, config)
            # written by a short shell process beside the bridge, as simple_launch does
            self.add_action(ExecuteProcess(
                cmd=["echo", _ShellQuoted(config), ">", path], shell=True,
                name=SimpleSubstitution(name, "_config")))
            self.node(f"ros_{gz}_bridge", "parameter_bridge", name=name,
                      parameters={"config_file": path})
        if images:
            remappings = [(SimpleSubstitution(b.gz_topic, ext),
                           SimpleSubstitution(b.ros_topic, ext))
                          for b in images for ext in _IMAGE_TRANSPORTS]
            self.node(f"ros_{gz}_image", "image_bridge", name=SimpleSubstitution(name, "_image"),
                      arguments=[b.gz_topic for b in images], remappings=remappings)

    def create_gz_clock_bridge(self: _Launcher, name: SubValue = "gz_clock_bridge") -> None:
        self.create_gz_bridge(GazeboBridge.clock(), name)

    def gz_world_tf(self: _Launcher, world_frame: SubValue = None) -> Any:
        """A static transform `world` -> Gazebo's world frame, when they differ."""
        if world_frame is None:
            world_frame = GazeboBridge.world()
        if world_frame == "world":
            return None
        return self.node("tf2_ros", "static_transform_publisher", name="gz_world_tf",
                         arguments=["--frame-id", "world", "--child-frame-id", world_frame])


def _remember_world(world_file: SubValue, gz_args: SubValue) -> None:
    """Reads the world's name from the SDF given to gz_launch, for GazeboBridge.world().

    The world may also hide among the arguments (`gz_launch('-r my.sdf')`): the first word
    that is an existing file is taken, as simple_launch does.
    """
    if not isinstance(world_file, str) or not (gz_args is None or isinstance(gz_args, str)):
        return
    words = f"{world_file} {gz_args or ''}".split()
    found = world_file if os.path.isfile(world_file) else next(
        (w for w in words if os.path.isfile(w)), None)
    name = world_name_in(found) if found else None
    if name:
        GazeboBridge.set_world_name(name)
    # simple_launch says what it found, once per world file, unless only listing arguments
    if only_show_args() or (found is not None and found in _announced_worlds):
        return
    if found is None:
        console.warn(f'Could not read Gazebo world @ "{world_file}"')
        return
    _announced_worlds.add(found)
    if name:
        console.info(f'Gazebo world "{name}" found @ {found}')
    else:
        console.warn(f"Could not get the name of Gazebo world {found}")


_announced_worlds: set[str] = set()


__all__ = ["GazeboBridge", "GazeboLauncher", "gazebo_message", "only_show_args",
           "reset_world_name", "ros_gz_prefix"]
