"""The Description: what a launch file says, as a lazy tree of entities.

These classes carry the plain launch API's names and keywords (`Node`, `GroupAction`,
`DeclareLaunchArgument`, ...) so that `launch` / `launch_ros` imports in user files map onto
them directly; the SimpleLauncher DSL builds the very same tree. Nothing is performed here:
values stay substitutions until `resolve` reads them against argument values.

Over 500 lines on purpose: it is the one catalogue of entity types, kept whole so each
launch name has one place to be looked up.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from ..errors import DslError, Origin, caller_origin
from .conditions import Condition
from .substitutions import SubValue, describe


class Entity:
    """Anything that can stand in a launch description."""

    condition: Condition | None = None
    origin: Origin | None = None

    def __init__(self, *, condition: Condition | None = None, **_: Any) -> None:
        """launch.Action's constructor, for third-party actions (`execute(context)`)."""
        self._init_entity(condition)

    def _init_entity(self, condition: Condition | None) -> None:
        self.condition = condition
        self.origin = caller_origin()

    def describe(self) -> str:
        return type(self).__name__


Action = Entity


def entity_list(value: Any, what: str = "actions") -> list[Any]:
    """Entities from a single one, a list, or a LaunchDescription; callables kept as-is."""
    if value is None:
        return []
    if isinstance(value, LaunchDescription):
        return list(value.entities)
    if isinstance(value, list | tuple):
        out: list[Any] = []
        for item in value:
            out.extend(entity_list(item, what))
        return out
    if isinstance(value, Entity) or callable(value):
        return [value]
    raise DslError(
        f"{what} must be launch actions, got {type(value).__name__} {value!r}", caller_origin()
    )


class LaunchDescription(Entity):
    def __init__(self, initial_entities: Iterable[Any] | None = None) -> None:
        self._init_entity(None)
        self.entities: list[Any] = entity_list(list(initial_entities or []))

    def add_action(self, action: Any) -> None:
        self.entities.extend(entity_list(action))

    add_entity = add_action


class DeclareLaunchArgument(Entity):
    """A launch argument. `py_type` is the Python type of a SimpleLauncher raw default."""

    def __init__(
        self,
        name: str,
        *,
        default_value: SubValue = None,
        description: str | None = None,
        choices: Iterable[str] | None = None,
        condition: Condition | None = None,
        py_type: str | None = None,
        **_: Any,
    ) -> None:
        self._init_entity(condition)
        if not isinstance(name, str) or not name:
            raise DslError(f"argument name must be a non-empty string, got {name!r}", self.origin)
        self.name = name
        self.default_value = default_value
        self.description = description
        self.choices = [str(c) for c in choices] if choices is not None else None
        self.py_type = py_type

    def describe(self) -> str:
        return f"argument {self.name}"


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
        for formatting in ("log_cmd", "output_format", "cached_output"):
            unknown.pop(formatting, None)
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
        **_: Any,
    ) -> None:
        self._init_entity(condition)
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


class Group(Entity):
    """A scope: namespace, condition and trigger apply to everything inside.

    Both `with sl.group(...)` and `GroupAction` become a Group. Scoped groups keep argument
    changes made inside (e.g. by an include) from leaking out, as launch's GroupAction does.
    """

    def __init__(
        self,
        children: list[Any] | None = None,
        *,
        namespace: SubValue = None,
        condition: Condition | None = None,
        when: Any = None,
        scoped: bool = True,
        launch_configurations: dict[Any, Any] | None = None,
        label: str | None = None,
        forwarding: bool = True,
    ) -> None:
        self._init_entity(condition)
        self.forwarding = forwarding
        self.children: list[Any] = list(children or [])
        self.namespace = namespace
        self.when = when
        self.scoped = scoped
        self.launch_configurations = launch_configurations or {}
        self.label = label
        self.dsl_owner: Any = None

    def describe(self) -> str:
        return self.label or "group"


def GroupAction(
    actions: Iterable[Any],
    *,
    condition: Condition | None = None,
    scoped: bool = True,
    forwarding: bool = True,
    launch_configurations: dict[Any, Any] | None = None,
    **_: Any,
) -> Group:
    group = Group(
        entity_list(list(actions)),
        condition=condition,
        scoped=scoped or not forwarding,
        launch_configurations=launch_configurations,
        forwarding=forwarding,
    )
    group.origin = caller_origin()
    return group


class PushRosNamespace(Entity):
    def __init__(self, namespace: SubValue, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.namespace = namespace


PushROSNamespace = PushRosNamespace


class SetParameter(Entity):
    """A parameter given to every node that follows in the same scope."""

    def __init__(self, name: SubValue, value: Any, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.name = name
        self.value = value


class SetParametersFromFile(Entity):
    """A parameter file given to every node that follows in the same scope."""

    def __init__(self, filename: SubValue, condition: Condition | None = None, **_: Any) -> None:
        self._init_entity(condition)
        self.filename = filename


class SetRemap(Entity):
    def __init__(self, src: SubValue, dst: SubValue, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.src = src
        self.dst = dst


class SetEnvironmentVariable(Entity):
    def __init__(self, name: SubValue, value: SubValue, condition: Condition | None = None)\
            -> None:
        self._init_entity(condition)
        self.name = name
        self.value = value


class UnsetEnvironmentVariable(Entity):
    def __init__(self, name: SubValue, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.name = name


class SetLaunchConfiguration(Entity):
    def __init__(self, name: SubValue, value: SubValue, condition: Condition | None = None)\
            -> None:
        self._init_entity(condition)
        self.name = name
        self.value = value


class LaunchDescriptionSource:
    def __init__(self, launch_file_path: SubValue) -> None:
        self.location = launch_file_path


PythonLaunchDescriptionSource = AnyLaunchDescriptionSource = LaunchDescriptionSource


class IncludeLaunchDescription(Entity):
    def __init__(
        self,
        launch_description_source: Any,
        *,
        launch_arguments: Any = None,
        condition: Condition | None = None,
        **_: Any,
    ) -> None:
        self._init_entity(condition)
        if isinstance(launch_description_source, LaunchDescriptionSource):
            self.location: SubValue = launch_description_source.location
        else:
            self.location = launch_description_source
        self.launch_arguments = pair_list(launch_arguments, "launch_arguments", self.origin)

    def describe(self) -> str:
        return f"include {describe(self.location)}"


def pair_list(value: Any, what: str, origin: Origin | None = None) -> list[tuple[Any, Any]]:
    """Remappings, launch and xacro arguments: a dict or (key, value) pairs, as pairs."""
    if value is None:
        return []
    if isinstance(value, dict):
        return list(value.items())
    pairs: list[tuple[Any, Any]] = []
    try:
        items = list(value)
    except TypeError:
        items = [value]
    for item in items:
        if isinstance(item, dict):
            pairs.extend(item.items())
        elif isinstance(item, list | tuple) and len(item) == 2:
            pairs.append((item[0], item[1]))
        else:
            raise DslError(f"{what} must be a dict or (key, value) pairs, got {item!r}",
                           origin or caller_origin())
    return pairs


class LogInfo(Entity):
    def __init__(self, *, msg: SubValue, condition: Condition | None = None, **_: Any) -> None:
        self._init_entity(condition)
        self.msg = msg


class CallService(Entity):
    """`sl.call_service`: wait for a service, call it with a request built from a dict."""

    def __init__(self, server: SubValue, request: dict[str, Any] | None, verbosity: SubValue)\
            -> None:
        self._init_entity(None)
        self.server = server
        self.request = request or {}
        self.verbosity = verbosity


class SetParameters(Entity):
    """`sl.set_parameters`: wait for a node, set parameters through its service."""

    def __init__(self, node_name: SubValue, parameters: dict[str, Any], verbosity: SubValue)\
            -> None:
        self._init_entity(None)
        self.node_name = node_name
        self.parameters = dict(parameters)
        self.verbosity = verbosity


class TimerAction(Entity):
    def __init__(self, *, period: Any, actions: Iterable[Any],
                 condition: Condition | None = None, **_: Any) -> None:
        # launch_ros's RosTimer counts ROS time; tuilaunch counts wall time for both
        self._init_entity(condition)
        self.period = period
        self.actions = entity_list(list(actions))


class Shutdown(Entity):
    """An action that ends the whole launch (also `EmitEvent(event=Shutdown())`)."""

    def __init__(self, *, reason: SubValue = "reason not given", condition: Condition | None
                 = None, **_: Any) -> None:
        self._init_entity(condition)
        self.reason = reason


EMITTED_EVENTS: dict[type, Callable[[Any, Condition | None], Entity]] = {}
"""Event class -> the entity that performs `EmitEvent(event=...)`; one line per event kind."""


def EmitEvent(*, event: Any, condition: Condition | None = None, **_: Any) -> Entity:
    if isinstance(event, Shutdown):
        event.condition = condition
        event.origin = caller_origin()
        return event
    for kind, make in EMITTED_EVENTS.items():
        if isinstance(event, kind):
            entity = make(event, condition)
            entity.origin = caller_origin()
            return entity
    raise DslError(f"tuilaunch does not support EmitEvent({type(event).__name__}) yet",
                   caller_origin())


class ActionMatcher:
    """launch.events.matches_action(action): picks the process an event is about."""

    def __init__(self, action: Any) -> None:
        self.target = action

    def __call__(self, candidate: Any) -> bool:
        return candidate is self.target


def matches_action(target_action: Any) -> ActionMatcher:
    return ActionMatcher(target_action)


class ShutdownProcess:
    """launch.events.process.ShutdownProcess: stop one process (SIGINT, then escalate)."""

    def __init__(self, *, process_matcher: Any) -> None:
        self.process_matcher = process_matcher


class StopProcess(Entity):
    """What EmitEvent(ShutdownProcess(...)) does: stop the matched process."""

    def __init__(self, target: Any, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.target = target


EMITTED_EVENTS[ShutdownProcess] = lambda event, condition: StopProcess(
    getattr(event.process_matcher, "target", None), condition)


class AppendEnvironmentVariable(Entity):
    """Adds to a variable's value with a separator (launch.actions.AppendEnvironmentVariable)."""

    def __init__(self, name: SubValue, value: SubValue, prepend: Any = False,
                 separator: SubValue = ":", condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.name, self.value = name, value
        self.prepend, self.separator = prepend, separator


class EnvironmentStack(Entity):
    """PushEnvironment / PopEnvironment / ResetEnvironment and the launch-configuration ones."""

    def __init__(self, what: str, op: str, values: dict[Any, Any] | None = None,
                 condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.what, self.op, self.values = what, op, values


def PushEnvironment(condition: Condition | None = None, **_: Any) -> EnvironmentStack:
    return EnvironmentStack("env", "push", condition=condition)


def PopEnvironment(condition: Condition | None = None, **_: Any) -> EnvironmentStack:
    return EnvironmentStack("env", "pop", condition=condition)


def ResetEnvironment(condition: Condition | None = None, **_: Any) -> EnvironmentStack:
    return EnvironmentStack("env", "reset", condition=condition)


def PushLaunchConfigurations(condition: Condition | None = None, **_: Any) -> EnvironmentStack:
    return EnvironmentStack("config", "push", condition=condition)


def PopLaunchConfigurations(condition: Condition | None = None, **_: Any) -> EnvironmentStack:
    return EnvironmentStack("config", "pop", condition=condition)


def ResetLaunchConfigurations(launch_configurations: dict[Any, Any] | None = None,
                              condition: Condition | None = None, **_: Any) -> EnvironmentStack:
    return EnvironmentStack("config", "reset", launch_configurations or {}, condition)


class UnsetLaunchConfiguration(Entity):
    def __init__(self, name: SubValue, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.name = name


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


def SetUseSimTime(value: Any, condition: Condition | None = None, **_: Any) -> SetParameter:
    action = SetParameter("use_sim_time", value, condition)
    action.origin = caller_origin()
    return action


def SetROSLogDir(new_log_dir: SubValue, condition: Condition | None = None, **_: Any)\
        -> SetEnvironmentVariable:
    action = SetEnvironmentVariable("ROS_LOG_DIR", new_log_dir, condition)
    action.origin = caller_origin()
    return action


class OpaqueFunction(Entity):
    """A Python function run with the launch context: at resolve time, or, inside an event
    handler, a timer or OnShutdown, by the supervisor when that event happens."""

    def __init__(self, *, function: Callable[..., Any], args: Iterable[Any] | None = None,
                 kwargs: dict[str, Any] | None = None, condition: Condition | None = None)\
            -> None:
        self._init_entity(condition)
        self.function = function
        self.args = list(args or [])
        self.kwargs = dict(kwargs or {})


class DslOpaque(Entity):
    """SimpleLauncher's opaque-function mode: `sl.arg()` gives Python values inside."""

    def __init__(self, launcher: Any, function: Callable[[], Any]) -> None:
        self._init_entity(None)
        self.launcher = launcher
        self.function = function


# --- event handlers -------------------------------------------------------------------


class EventHandler(Entity):
    """launch.event_handlers.*: actions run when a process starts, exits, prints, ..."""

    on: str = ""

    def __init__(self, target_action: Any = None, handler: Any = None, io: str | None = None)\
            -> None:
        self._init_entity(None)
        self.target = target_action
        self.handler = handler
        self.io = io


class OnProcessStart(EventHandler):
    on = "start"

    def __init__(self, *, target_action: Any = None, on_start: Any = None, **_: Any) -> None:
        super().__init__(target_action, on_start)


class OnProcessExit(EventHandler):
    on = "exit"

    def __init__(self, *, target_action: Any = None, on_exit: Any = None, **_: Any) -> None:
        super().__init__(target_action, on_exit)


class OnExecutionComplete(EventHandler):
    on = "exit"

    def __init__(self, *, target_action: Any = None, on_completion: Any = None, **_: Any)\
            -> None:
        super().__init__(target_action, on_completion)


class OnProcessIO(EventHandler):
    on = "io"

    def __init__(self, *, target_action: Any = None, on_stdin: Any = None,
                 on_stdout: Any = None, on_stderr: Any = None, **_: Any) -> None:
        io = "stdout" if on_stdout is not None else "stderr" if on_stderr is not None else "stdin"
        super().__init__(target_action, on_stdout or on_stderr or on_stdin, io)


class OnShutdown(EventHandler):
    on = "shutdown"

    def __init__(self, *, on_shutdown: Any = None, **_: Any) -> None:
        super().__init__(None, on_shutdown)


class RegisterEventHandler(Entity):
    def __init__(self, event_handler: EventHandler, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        if not isinstance(event_handler, EventHandler):
            raise DslError(
                f"RegisterEventHandler needs an event handler, got {event_handler!r}", self.origin
            )
        self.handler = event_handler


class IoCallbacks(Entity):
    """Python callbacks of an OnProcessIO group, called with each output event at run time."""

    def __init__(self, callbacks: list[Callable[[Any], Any]], launcher: Any = None) -> None:
        self._init_entity(None)
        self.callbacks = callbacks
        self.launcher = launcher
