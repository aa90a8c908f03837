"""What runs: a Node, an ExecuteProcess (ExecuteLocal), composable nodes and their
containers (launch_ros.actions / launch.actions)."""

from __future__ import annotations

from typing import Any

from ...errors import DslError, caller_origin
from ..conditions import Condition
from ..substitutions import SubValue, describe
from .base import Entity


class Node(Entity):
    """A ROS node process (launch_ros.actions.Node)."""

    kind = "node"

    def __init__(
        self,
        *,
        executable: SubValue = None,
        package: SubValue = None,
        name: SubValue = None,
        namespace: SubValue = None,
        exec_name: SubValue = None,
        parameters: Any = None,
        remappings: Any = None,
        ros_arguments: Any = None,
        arguments: Any = None,
        condition: Condition | None = None,
        output: Any = "screen",
        respawn: Any = False,
        respawn_delay: Any = None,
        respawn_max_retries: int | None = None,
        prefix: Any = None,
        env: dict[Any, Any] | None = None,
        additional_env: dict[Any, Any] | None = None,
        cwd: SubValue = None,
        sigterm_timeout: Any = None,
        sigkill_timeout: Any = None,
        emulate_tty: Any = None,
        node_name: SubValue = None,
        node_executable: SubValue = None,
        node_namespace: SubValue = None,
        **unknown: Any,
    ) -> None:
        self._init_entity(condition)
        self.on_exit: Any = unknown.pop("on_exit", None)
        # launch_ros hands the rest to ExecuteProcess: shell runs the command through
        # /bin/sh (controller_manager's spawner helpers set it); the others only format
        # launch's own output
        self.shell = bool(unknown.pop("shell", False))
        self.log_cmd = bool(unknown.pop("log_cmd", False))
        self.output_format: str | None = unknown.pop("output_format", None)
        unknown.pop("cached_output", None)  # only for code reading launch's own buffers
        if unknown:
            names = ", ".join(sorted(unknown))
            raise DslError(
                f"Node() got unknown argument(s): {names}",
                self.origin,
                hint="Node takes package, executable, name, namespace, parameters, remappings, "
                "arguments, ros_arguments, output, respawn, respawn_delay, prefix, env, "
                "additional_env, cwd",
            )
        executable = executable if executable is not None else node_executable
        if executable is None:
            raise DslError("Node() needs an executable", self.origin)
        self.package = package
        self.executable = executable
        self.name = name if name is not None else node_name
        self.namespace = namespace if namespace is not None else node_namespace
        self.exec_name = exec_name
        self.parameters = parameters
        self.remappings = remappings
        self.ros_arguments = ros_arguments
        self.arguments = arguments
        self.output = output
        self.respawn = respawn
        self.respawn_delay = respawn_delay
        self.respawn_max_retries = respawn_max_retries
        self.prefix = prefix
        self.env = env
        self.additional_env = additional_env
        self.cwd = cwd
        self.sigterm_timeout = sigterm_timeout
        self.sigkill_timeout = sigkill_timeout
        self.emulate_tty = emulate_tty
        self.components: list[ComposableNode] = []

    def describe(self) -> str:
        return f"node {describe(self.package)}/{describe(self.executable)}"


class ExecuteProcess(Entity):
    kind = "process"

    def __init__(
        self,
        *,
        cmd: Any,
        name: SubValue = None,
        cwd: SubValue = None,
        env: dict[Any, Any] | None = None,
        additional_env: dict[Any, Any] | None = None,
        shell: bool = False,
        output: Any = "screen",
        respawn: Any = False,
        respawn_delay: Any = None,
        respawn_max_retries: int | None = None,
        prefix: Any = None,
        condition: Condition | None = None,
        sigterm_timeout: Any = None,
        sigkill_timeout: Any = None,
        emulate_tty: Any = None,
        on_exit: Any = None,
        log_cmd: bool = False,
        output_format: str | None = None,
        **_: Any,
    ) -> None:
        self._init_entity(condition)
        self.log_cmd = bool(log_cmd)
        self.output_format = output_format
        self.emulate_tty = emulate_tty
        self.on_exit = on_exit
        self.cmd = cmd
        self.name = name
        self.cwd = cwd
        self.env = env
        self.additional_env = additional_env
        self.shell = shell
        self.output = output
        self.respawn = respawn
        self.respawn_delay = respawn_delay
        self.respawn_max_retries = respawn_max_retries
        self.prefix = prefix
        self.sigterm_timeout = sigterm_timeout
        self.sigkill_timeout = sigkill_timeout

    def describe(self) -> str:
        return f"process {describe(self.cmd)}"


class ComposableNode:
    """A component to load into a container (launch_ros.descriptions.ComposableNode)."""

    def __init__(
        self,
        *,
        package: SubValue,
        plugin: SubValue,
        name: SubValue = None,
        namespace: SubValue = None,
        parameters: Any = None,
        remappings: Any = None,
        extra_arguments: Any = None,
        condition: Condition | None = None,
        **_: Any,
    ) -> None:
        self.package = package
        self.plugin = plugin
        self.name = name
        self.namespace = namespace
        self.parameters = parameters
        self.remappings = remappings
        self.extra_arguments = extra_arguments
        self.condition = condition
        self.origin = caller_origin()


class ComposableNodeContainer(Node):
    kind = "container"

    def __init__(
        self,
        *,
        name: SubValue,
        namespace: SubValue = None,
        package: SubValue = "rclcpp_components",
        executable: SubValue = "component_container",
        composable_node_descriptions: list[ComposableNode] | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init__(
            package=package, executable=executable, name=name, namespace=namespace, **kwargs
        )
        self.components = list(composable_node_descriptions or [])


class LoadComposableNodes(Entity):
    def __init__(
        self,
        *,
        composable_node_descriptions: list[ComposableNode],
        target_container: Any,
        condition: Condition | None = None,
        **_: Any,
    ) -> None:
        self._init_entity(condition)
        self.components = list(composable_node_descriptions)
        self.target_container = target_container


class Executable:
    """launch.descriptions.Executable: what ExecuteLocal runs."""

    def __init__(self, *, cmd: Any, prefix: Any = None, name: SubValue = None,
                 cwd: SubValue = None, env: dict[Any, Any] | None = None,
                 additional_env: dict[Any, Any] | None = None, **_: Any) -> None:
        self.cmd, self.prefix, self.name = cmd, prefix, name
        self.cwd, self.env, self.additional_env = cwd, env, additional_env


def ExecuteLocal(*, process_description: Executable, **kwargs: Any) -> ExecuteProcess:
    d = process_description
    process = ExecuteProcess(cmd=d.cmd, prefix=d.prefix, name=d.name, cwd=d.cwd, env=d.env,
                             additional_env=d.additional_env, **kwargs)
    process.origin = caller_origin()
    return process
