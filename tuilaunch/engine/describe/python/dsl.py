"""SimpleLauncher: the simple_launch DSL, building a Description of entities.

While tuilaunch loads a launch file, `from simple_launch import SimpleLauncher` resolves to
this class, so files written for simple_launch run unchanged.
"""

from __future__ import annotations

import ast
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

from ...errors import DslError, Origin, PackageError, caller_origin
from ...packages import package_share
from ..conditions import IfCondition, UnlessCondition
from ..entities import (
    CallService,
    ComposableNode,
    ComposableNodeContainer,
    DeclareLaunchArgument,
    DslOpaque,
    Group,
    IncludeLaunchDescription,
    IoCallbacks,
    LaunchDescription,
    LoadComposableNodes,
    LogInfo,
    Node,
    SetParameters,
    TriggerOn,
    pair_list,
)
from ..events import When
from ..ros_substitutions import Xacro
from ..substitutions import (
    LaunchConfiguration,
    PathJoin,
    PerformContext,
    PythonExpression,
    SimpleSubstitution,
    Substitution,
    SubValue,
    describe,
    flatten,
    is_lazy,
    perform,
    slash_join,
)
from ..values import yaml_single_quoted
from .gazebo import GZ_AXES, GazeboBridge, GazeboLauncher


def _raw_default(value: Any) -> tuple[Any, str]:
    """A raw Python default as launch text, and the type the argument form should edit."""
    if isinstance(value, bool):
        return str(value), "bool"
    if isinstance(value, int):
        return str(value), "int"
    if isinstance(value, float):
        return str(value), "float"
    if isinstance(value, list | tuple):
        # repr keeps a list a list for py_eval and opaque functions: "[255, 0, 0]"
        return repr(list(value)), "list"
    if value is None:
        return "", "str"
    return value, "str"


def literal(text: str) -> Any:
    """An argument string as the Python value an opaque function sees."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        lowered = text.strip().lower()
        if lowered in ("true", "false"):
            return lowered == "true"
        return text


def share_file(package: str, file_name: str, origin: Origin | None = None) -> str:
    """A file found below a package's share, the deepest folders first, as simple_launch's
    `find` walks it (`os.walk(..., topdown=False)`): `share/launch/x.py` wins over `share/x.py`.
    """
    share = package_share(package, origin)
    for root, _dirs, files in os.walk(share, topdown=False):
        if file_name in files:
            return os.path.join(root, file_name)
    raise PackageError(
        f"file '{file_name}' not found in the share of package '{package}' ({share})", origin,
        hint="give its folder (file_dir= / launch_dir=) or check the file name")


class _FindFile(Substitution):
    """simple_launch's `find` when some part is only known at resolve time."""

    def __init__(self, package: SubValue, file_name: SubValue, file_dir: SubValue) -> None:
        self.package, self.file_name, self.file_dir = package, file_name, file_dir
        self.origin = caller_origin()

    def perform(self, context: PerformContext) -> str:
        file_name = perform(self.file_name, context)
        if self.package is None:
            return file_name
        package = perform(self.package, context)
        if self.file_dir is None:
            return share_file(package, file_name, self.origin)
        return os.path.join(package_share(package, self.origin), perform(self.file_dir, context),
                            file_name)

    def describe(self) -> str:
        parts = [describe(p) for p in (self.package, self.file_dir, self.file_name) if p]
        return f"$(find {'/'.join(parts)})"


class SimpleLauncher(GazeboLauncher):
    """The entry point of the simple_launch DSL (the Gazebo helpers come from gazebo.py)."""

    def __init__(self, namespace: SubValue = "", use_sim_time: Any = None,
                 scope_included_files: bool = False) -> None:
        self.namespace = namespace or ""
        self.scope_included_files = scope_included_files
        self.sim_time: Any = None
        self.gz_axes: tuple[str, ...] = GZ_AXES
        self._context: PerformContext | None = None
        self._root = Group(namespace=self.namespace or None, scoped=False, label="root")
        self._stack: list[Group] = [self._root]
        self._container: tuple[str, list[ComposableNode]] | None = None
        if use_sim_time is None:
            return
        if isinstance(use_sim_time, bool):
            self.sim_time = self.declare_arg(
                "use_sim_time", use_sim_time,
                description="Force use_sim_time parameter of instantiated nodes")
        elif use_sim_time == "auto":
            from . import console
            from .gazebo import only_show_args
            from .sim_clock import clock_is_published

            if only_show_args():
                console.warn("This launch file will forward use_sim_time to all nodes if "
                             "/clock is advertized at the time of the launch")
                return
            self.sim_time = clock_is_published()
            console.info("SimpleLauncher(use_sim_time='auto'): " + (
                "found a /clock topic, forwarding use_sim_time:=True to all nodes"
                if self.sim_time else
                "no /clock topic found, forwarding use_sim_time:=False to all nodes"))
        else:
            raise DslError(
                f"use_sim_time must be None, True, False or 'auto', got {use_sim_time!r}",
                caller_origin())

    # --- arguments ---------------------------------------------------------------------

    def declare_arg(self, name: str, default_value: Any = None, description: str | None = None,
                    choices: Any = None, **kwargs: Any) -> Any:
        if self._context is not None:
            raise DslError(
                f"declare_arg('{name}') called inside the opaque function",
                caller_origin(),
                hint="declare arguments in the main body, before launch_description()")
        text, py_type = _raw_default(default_value)
        if choices is not None:
            choices = [_raw_default(c)[0] for c in choices]
        decl = DeclareLaunchArgument(name, default_value=text, description=description,
                                     choices=choices, py_type=py_type, **kwargs)
        self._root.children.insert(self._declarations_end(), decl)
        return self.arg(name)

    def _declarations_end(self) -> int:
        # Declarations go first so an argument is known wherever the file uses it, as
        # simple_launch adds them to the top-level group.
        return sum(1 for e in self._root.children if isinstance(e, DeclareLaunchArgument))

    def arg(self, name: str) -> Any:
        return self._try_perform(SimpleSubstitution(LaunchConfiguration(name)))

    def arg_map(self, *names: Any) -> dict[str, Any]:
        if len(names) == 1 and isinstance(names[0], list | tuple):
            names = tuple(names[0])
        return {name: self.arg(name) for name in names}

    def _try_perform(self, value: Any) -> Any:
        if self._context is None or isinstance(value, str):
            return value
        return literal(perform(value, self._context))

    # --- description ---------------------------------------------------------------------

    def launch_description(self, opaque_function: Callable[[], Any] | None = None) -> Any:
        if opaque_function is None:
            if self._context is not None:
                return [self._root]
            return LaunchDescription([self._root])
        if self._context is not None:
            raise DslError("launch_description(opaque_function=...) called inside an opaque "
                           "function", caller_origin())
        decls = [e for e in self._root.children if isinstance(e, DeclareLaunchArgument)]
        body = [e for e in self._root.children if not isinstance(e, DeclareLaunchArgument)]
        opaque = DslOpaque(self, opaque_function)

        def generate_launch_description() -> LaunchDescription:
            root = Group([*body, opaque], namespace=self.namespace or None, scoped=False,
                         label="root")
            return LaunchDescription([*decls, root])

        return generate_launch_description

    @contextmanager
    def opaque_scope(self, context: PerformContext) -> Iterator[Group]:
        """Runs the opaque function against resolved values, collecting into a fresh root."""
        saved = (self._context, self._root, self._stack)
        self._context = context
        self._root = Group(scoped=False, label="opaque")
        self._stack = [self._root]
        try:
            yield self._root
        finally:
            self._context, self._root, self._stack = saved

    @contextmanager
    def capture(self) -> Iterator[list[Any]]:
        """Collects what DSL calls add while an event callback runs, outside the Description."""
        saved = (self._root, self._stack)
        self._root = Group(scoped=False, label="event")
        self._stack = [self._root]
        try:
            yield self._root.children
        finally:
            self._root, self._stack = saved

    # --- groups ----------------------------------------------------------------------------

    @property
    def _current(self) -> Group:
        return self._stack[-1]

    @contextmanager
    def group(self, ns: SubValue = None, if_arg: Any = None, unless_arg: Any = None,
              if_condition: Any = None, unless_condition: Any = None,
              when: When | None = None) -> Iterator[SimpleLauncher]:
        origin = caller_origin()
        if self._container is not None:
            raise DslError(f"group blocks cannot be nested in container '{self._container[0]}'",
                           origin)
        given = [c for c in (if_arg, unless_arg, if_condition, unless_condition) if c is not None]
        if len(given) > 1:
            raise DslError(
                f"a group takes one condition, this one has {len(given)}", origin,
                hint="combine them with sl.py_eval(...) or nest two groups")
        condition = None
        if if_arg is not None:
            condition = IfCondition(self._arg_or_value(if_arg))
        elif unless_arg is not None:
            condition = UnlessCondition(self._arg_or_value(unless_arg))
        elif if_condition is not None:
            condition = IfCondition(if_condition)
        elif unless_condition is not None:
            condition = UnlessCondition(unless_condition)
        if condition is not None:
            condition.origin = origin
        if when is not None and not isinstance(when, When):
            raise DslError(f"when= takes a When(...), got {when!r}", origin)
        group = Group(namespace=ns, condition=condition, when=when)
        group.origin = origin
        group.dsl_owner = self
        self._current.children.append(group)
        self._stack.append(group)
        try:
            yield self
        finally:
            self._stack.pop()
            if when is not None and when.on == TriggerOn.IO:
                callbacks = [c for c in group.children if callable(c)]
                group.children = [IoCallbacks(callbacks, self)] if callbacks else []

    def _arg_or_value(self, value: Any) -> Any:
        if isinstance(value, str):
            return LaunchConfiguration(value)
        return value

    @contextmanager
    def container(self, name: SubValue, namespace: SubValue = "", existing: bool = False,
                  package: SubValue = "rclcpp_components",
                  executable: SubValue = "component_container",
                  **container_args: Any) -> Iterator[SimpleLauncher]:
        components: list[ComposableNode] = []
        self._container = (describe(name), components)
        try:
            yield self
        finally:
            self._container = None
        if existing:
            self.add_action(LoadComposableNodes(composable_node_descriptions=components,
                                                target_container=name))
        else:
            self.add_action(ComposableNodeContainer(
                name=name, namespace=namespace, package=package, executable=executable,
                composable_node_descriptions=components, **container_args))

    def add_action(self, action: Any) -> Any:
        if isinstance(action, list | tuple):
            for item in action:
                self.add_action(item)
            return action
        group = self._current
        if callable(action) and not hasattr(action, "condition"):
            if group.when is None or group.when.on != TriggerOn.IO:
                raise DslError("add_action() got a function outside an OnProcessIO group",
                               caller_origin(), hint="functions receive OnProcessIO events")
        group.children.append(action)
        return action

    entity = add_action

    # --- nodes -------------------------------------------------------------------------------

    def node(self, package: SubValue = None, executable: SubValue = None,
             plugin: SubValue = None, **node_args: Any) -> Any:
        origin = caller_origin()
        if "parameters" in node_args:
            node_args["parameters"] = parameter_list(node_args["parameters"])
        if "remappings" in node_args:
            node_args["remappings"] = pair_list(node_args["remappings"], "remappings")
        if isinstance(node_args.get("arguments"), str):
            node_args["arguments"] = node_args["arguments"].split()
        if self.sim_time is not None:
            node_args["parameters"] = with_sim_time(node_args.get("parameters", []),
                                                    self.sim_time)
        if self._container is not None:
            if plugin is None:
                raise DslError("a node in a container needs plugin=...", origin)
            if isinstance(plugin, str) and "::" not in plugin and isinstance(package, str):
                plugin = f"{package}::{plugin}"
            component = ComposableNode(package=package, plugin=plugin, **node_args)
            component.origin = origin
            self._container[1].append(component)
            return component
        if package is None and executable is None:
            raise DslError("node() needs a package and an executable", origin)
        if executable is None:
            executable = package
        entity = Node(package=package, executable=executable, **node_args)
        entity.origin = origin
        return self.add_action(entity)

    def log_info(self, msg: SubValue) -> LogInfo:
        entity = LogInfo(msg=msg)
        return self.add_action(entity)

    def include(self, package: SubValue = None, launch_file: SubValue = None,
                launch_dir: SubValue = None, launch_arguments: Any = None) -> Any:
        origin = caller_origin()
        if launch_file is None:
            raise DslError("include() needs a launch_file", origin)
        location = _FindFile(package, launch_file, launch_dir)
        location.origin = origin
        inclusion = IncludeLaunchDescription(location,
                                             launch_arguments=pair_list(launch_arguments,
                                                                        "launch_arguments"))
        inclusion.origin = origin
        if self.scope_included_files:
            scope = Group([inclusion], scoped=True, label="scoped include")
            scope.origin = origin
            return self.add_action(scope)
        return self.add_action(inclusion)

    def call_service(self, server: SubValue, request: dict[str, Any] | None = None,
                     verbosity: SubValue = "", **_: Any) -> CallService:
        if request is not None and not isinstance(request, dict):
            raise DslError(f"call_service request must be a dict, got {request!r}",
                           caller_origin())
        return self.add_action(CallService(server, request, verbosity))

    service = call_service

    def set_parameters(self, node_name: SubValue, parameters: dict[str, Any] | None = None,
                       verbosity: SubValue = "", **_: Any) -> SetParameters:
        if parameters is not None and not isinstance(parameters, dict):
            raise DslError(f"set_parameters takes a dict, got {parameters!r}", caller_origin())
        entity = SetParameters(node_name, parameters or {}, verbosity)
        return self.add_action(entity)

    def rviz(self, config_file: SubValue = None, warnings: bool = False) -> Any:
        args: list[Any] = [] if config_file is None else ["-d", config_file]
        if not warnings:
            args += ["--ros-args", "--log-level", "FATAL"]
        return self.node("rviz2", "rviz2", arguments=args)

    def robot_description(self, package: SubValue = None, description_file: SubValue = None,
                          description_dir: SubValue = None, xacro_args: Any = None) -> Any:
        path = self.find(package, description_file, description_dir)
        if isinstance(path, str) and path.endswith(".urdf") and xacro_args is None:
            with open(path) as handle:
                return handle.read()
        description = Xacro(path, pair_list(xacro_args, "xacro_args"))
        if self._context is None:
            return description
        # in an opaque function too, as the parameter launch_ros reads from simple_launch's
        # quoted xacro output: line breaks folded as YAML folds them
        return yaml_single_quoted(perform(description, self._context))

    def robot_state_publisher(self, package: SubValue = None, description_file: SubValue = None,
                              description_dir: SubValue = None, xacro_args: Any = None,
                              namespaced_tf: bool = False, prefix_gz_plugins: bool = False,
                              **node_args: Any) -> Any:
        if prefix_gz_plugins:
            raise DslError("robot_state_publisher(prefix_gz_plugins=True) is not supported "
                           "(simple_launch 1.10 removed it)", caller_origin(),
                           hint="remove it; give frame names in the robot's description instead")
        description = self.robot_description(package, description_file, description_dir,
                                             xacro_args)
        params = parameter_list(node_args.pop("parameters", []))
        node_args["parameters"] = [*params, {"robot_description": description}]
        if namespaced_tf:
            # simple_launch 1.9: /tf and /tf_static stay inside the robot's namespace
            remaps = pair_list(node_args.pop("remappings", None), "remappings")
            node_args["remappings"] = [*remaps, ("/tf", "tf"), ("/tf_static", "tf_static")]
        return self.node("robot_state_publisher", "robot_state_publisher", **node_args)

    def joint_state_publisher(self, use_gui: Any = True, **node_args: Any) -> None:
        gui = str(use_gui) if isinstance(use_gui, bool) else use_gui
        # simple_launch passes the keywords as one dict, even an empty one (an empty file)
        params = [node_args]
        self.node("joint_state_publisher", parameters=params, condition=UnlessCondition(gui))
        self.node("joint_state_publisher_gui", parameters=params, condition=IfCondition(gui))

    # --- values ---------------------------------------------------------------------------

    def py_eval(self, *elems: Any) -> Any:
        if self._context is not None:
            return PythonExpression(list(elems)).evaluate(self._context)
        return SimpleSubstitution(PythonExpression(list(elems)))

    def find(self, package: SubValue = None, file_name: SubValue = None,
             file_dir: SubValue = None) -> Any:
        origin = caller_origin()
        if is_lazy([package, file_name, file_dir]):
            lazy = _FindFile(package, file_name, file_dir)
            lazy.origin = origin
            if file_name is None:
                return SimpleSubstitution(PathJoin([lazy]))
            return self._try_perform(SimpleSubstitution(lazy))
        if file_name is None:
            return str(package_share(str(package), origin)) if package else None
        if package is None:
            return str(file_name)
        if file_dir is not None:
            return os.path.join(package_share(str(package), origin), str(file_dir),
                                str(file_name))
        return share_file(str(package), str(file_name), origin)

    def name_join(self, *elems: Any) -> Any:
        return self._try_perform(SimpleSubstitution(list(elems)))

    def path_join(self, *paths: Any) -> Any:
        joined = SimpleSubstitution()
        for path in paths:
            joined = slash_join(joined, path)
        return self._try_perform(joined)

    @staticmethod
    def ros_version() -> str:
        return os.environ.get("ROS_DISTRO", "jazzy")


def parameter_list(value: Any) -> list[Any]:
    """Node parameters in any form simple_launch accepts, as an ordered list."""
    if value is None:
        return []
    if isinstance(value, dict | str | Substitution):
        return [value]
    if isinstance(value, list | tuple):
        if value and all(isinstance(v, dict) for v in value):
            # simple_launch merges a list of dicts into one (one parameter file)
            return [{k: v for item in value for k, v in item.items()}]
        if value and all(isinstance(v, list | tuple) and len(v) == 2 for v in value):
            return [dict(value)]
        return list(value)
    return [value]


def with_sim_time(params: list[Any], sim_time: Any) -> list[Any]:
    """use_sim_time as simple_launch adds it: into the first dict unless it sets it, after a
    first YAML file that does not mention it, never after a first substitution."""
    if not params:
        return [{"use_sim_time": sim_time}]
    first = params[0]
    if isinstance(first, dict):
        if "use_sim_time" in first:
            return params
        return [{**first, "use_sim_time": sim_time}, *params[1:]]
    if isinstance(first, str):
        try:
            with open(first, encoding="utf-8") as handle:
                mentioned = any(line.strip().startswith("use_sim_time") for line in handle)
        except OSError:
            return params
        return params if mentioned else [*params, {"use_sim_time": sim_time}]
    return params


__all__ = ["GazeboBridge", "SimpleLauncher", "flatten", "share_file"]
