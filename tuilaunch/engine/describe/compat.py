"""Module objects standing in for `launch`, `launch_ros` and `simple_launch` in user files."""

from __future__ import annotations

from types import ModuleType
from typing import Any

from ..plan import params
from . import conditions, entities, events, gazebo, substitutions
from .dsl import SimpleLauncher


def _module(name: str, **members: Any) -> ModuleType:
    module = ModuleType(name)
    module.__dict__.update(members)
    module.__dict__["__all__"] = sorted(members)
    return module


def _pick(source: ModuleType, *names: str) -> dict[str, Any]:
    return {name: getattr(source, name) for name in names}


class LaunchContext(substitutions.PerformContext):
    pass


def build_modules() -> dict[str, ModuleType]:
    subs = _pick(substitutions, "LaunchConfiguration", "TextSubstitution", "PythonExpression",
                 "Command", "EnvironmentVariable", "FindExecutable", "PathJoinSubstitution",
                 "ThisLaunchFile", "ThisLaunchFileDir", "LocalSubstitution", "AnonName",
                 "NotSubstitution", "AndSubstitution", "OrSubstitution", "EqualsSubstitution",
                 "NotEqualsSubstitution", "IfElseSubstitution", "Substitution")
    actions = _pick(entities, "DeclareLaunchArgument", "GroupAction", "IncludeLaunchDescription",
                    "LogInfo", "TimerAction", "RegisterEventHandler", "OpaqueFunction",
                    "ExecuteProcess", "SetEnvironmentVariable", "UnsetEnvironmentVariable",
                    "SetLaunchConfiguration", "EmitEvent", "Shutdown", "Action")
    handlers = _pick(entities, "OnProcessStart", "OnProcessExit", "OnProcessIO",
                     "OnExecutionComplete", "OnShutdown")
    conds = _pick(conditions, "IfCondition", "UnlessCondition", "LaunchConfigurationEquals",
                  "LaunchConfigurationNotEquals", "Condition")
    sources = _pick(entities, "PythonLaunchDescriptionSource", "AnyLaunchDescriptionSource",
                    "LaunchDescriptionSource")
    # XML and YAML files are read by extension whatever source class names them
    sources["FrontendLaunchDescriptionSource"] = entities.LaunchDescriptionSource
    xml_source = {"XMLLaunchDescriptionSource": entities.LaunchDescriptionSource}
    yaml_source = {"YAMLLaunchDescriptionSource": entities.LaunchDescriptionSource}
    ros_actions = _pick(entities, "Node", "PushRosNamespace", "PushROSNamespace", "SetParameter",
                        "SetRemap", "ComposableNodeContainer", "LoadComposableNodes")
    ros_subs = _pick(substitutions, "FindPackageShare", "FindPackagePrefix")
    param_value = {"ParameterValue": params.ParameterValue}

    launch = _module("launch", LaunchDescription=entities.LaunchDescription,
                     LaunchContext=LaunchContext, Substitution=substitutions.Substitution,
                     Action=entities.Action, Condition=conditions.Condition)
    modules = {
        "launch": launch,
        "launch.actions": _module("launch.actions", **actions),
        "launch.substitutions": _module("launch.substitutions", **subs),
        "launch.conditions": _module("launch.conditions", **conds),
        "launch.event_handlers": _module("launch.event_handlers", **handlers),
        "launch.events": _module("launch.events", Shutdown=entities.Shutdown),
        "launch.launch_description_sources": _module("launch.launch_description_sources",
                                                     **sources),
        "launch.launch_context": _module("launch.launch_context", LaunchContext=LaunchContext),
        "launch_ros": _module("launch_ros"),
        "launch_ros.actions": _module("launch_ros.actions", **ros_actions),
        "launch_ros.substitutions": _module("launch_ros.substitutions", FindPackage=ros_subs[
            "FindPackagePrefix"], **ros_subs),
        "launch_ros.descriptions": _module("launch_ros.descriptions",
                                           ComposableNode=entities.ComposableNode, **param_value),
        "launch_ros.parameter_descriptions": _module("launch_ros.parameter_descriptions",
                                                     **param_value),
        "launch_xml": _module("launch_xml"),
        "launch_xml.launch_description_sources": _module(
            "launch_xml.launch_description_sources", **xml_source),
        "launch_yaml": _module("launch_yaml"),
        "launch_yaml.launch_description_sources": _module(
            "launch_yaml.launch_description_sources", **yaml_source),
        "simple_launch": _module("simple_launch", SimpleLauncher=SimpleLauncher,
                                 SimpleSubstitution=substitutions.SimpleSubstitution,
                                 GazeboBridge=gazebo.GazeboBridge),
        "simple_launch.gazebo": _module("simple_launch.gazebo", **_pick(
            gazebo, "GazeboBridge", "ros_gz_prefix", "only_show_args")),
        "simple_launch.simple_substitution": _module("simple_launch.simple_substitution", **_pick(
            substitutions, "SimpleSubstitution", "flatten")),
        "simple_launch.events": _module("simple_launch.events", **_pick(
            events, "When", "OnProcessStart", "OnProcessExit", "OnProcessIO",
            "OnExecutionComplete", "OnShutdown")),
    }
    # `import launch.actions` binds `launch` and reads its attribute `actions`
    for name, module in modules.items():
        if "." in name:
            parent_name, child = name.rsplit(".", 1)
            setattr(modules[parent_name], child, module)
    return modules
