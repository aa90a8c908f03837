"""What shapes the scope of what follows: groups, namespaces, parameters and remappings
for every node, environment variables, launch configurations and their stacks, includes."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from ...errors import caller_origin
from ..conditions import Condition
from ..substitutions import SubValue, describe
from .base import Entity, entity_list, pair_list


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


class NameValue(Entity):
    """An action that sets one name to one value in its scope (a parameter, an environment
    variable, a launch configuration)."""

    def __init__(self, name: SubValue, value: Any, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.name = name
        self.value = value


class SetParameter(NameValue):
    """A parameter given to every node that follows in the same scope."""


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


class SetEnvironmentVariable(NameValue):
    """An environment variable of the processes that follow in the same scope."""


class UnsetEnvironmentVariable(Entity):
    def __init__(self, name: SubValue, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.name = name


class SetLaunchConfiguration(NameValue):
    """A launch configuration ($(var name)) for what follows in the same scope."""


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


def SetUseSimTime(value: Any, condition: Condition | None = None, **_: Any) -> SetParameter:
    action = SetParameter("use_sim_time", value, condition)
    action.origin = caller_origin()
    return action


def SetROSLogDir(new_log_dir: SubValue, condition: Condition | None = None, **_: Any)\
        -> SetEnvironmentVariable:
    action = SetEnvironmentVariable("ROS_LOG_DIR", new_log_dir, condition)
    action.origin = caller_origin()
    return action
