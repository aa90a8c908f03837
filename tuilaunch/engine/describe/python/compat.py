"""`launch`, `launch_ros` and `simple_launch` as packages with launch's module tree.

While a launch file loads, `import launch.substitutions.command`, `from launch.utilities
import perform_substitutions` or `launch.SomeSubstitutionsType` must work as with ROS's own
packages, because third-party extensions (nav2_common, ros2_control helpers) import from
where launch defines each name. The tree is built from NAMES, one row per public name at the
module that defines it: a package also offers every name of its direct submodules, as launch's
`__init__` files do. A name launch has and tuilaunch does not is listed as UNSUPPORTED, so a
file using it fails with "tuilaunch does not support launch.actions.X yet".

Other helpers add their names with rows of their own (`register(...)`), e.g. lifecycle nodes.
"""

from __future__ import annotations

import logging
from types import ModuleType
from typing import Any

from ...errors import LaunchError
from .. import conditions as c
from .. import entities as e
from .. import logic_substitutions as ls
from .. import parameter_files as pf
from .. import ros_substitutions as rs
from .. import substitutions as s
from .. import values as params
from . import launch_events as ev
from . import launch_utilities as u
from .dsl import SimpleLauncher

ROOTS = ("launch", "launch_ros", "simple_launch", "launch_xml", "launch_yaml")


class _Unsupported:
    def __repr__(self) -> str:
        return "UNSUPPORTED"


UNSUPPORTED: Any = _Unsupported()
"""A name launch defines and tuilaunch does not provide (yet)."""


class InvalidLaunchFileError(LaunchError):
    def __init__(self, extension: str = "", *, likely_errors: Any = None) -> None:
        super().__init__(f"invalid launch file {extension}".strip())


class LaunchContext(s.PerformContext):
    """launch.LaunchContext; extensions mostly receive one, some build their own."""

    def __init__(self, configurations: dict[str, str] | None = None, *_: Any, **__: Any)\
            -> None:
        super().__init__(dict(configurations or {}))


def _get_logger(name: str | None = None) -> logging.Logger:
    return logging.getLogger(name or "launch")


SomeSubstitutionsType = Any
SomeSubstitutionsType_types_tuple = (str, s.Substitution)
SomeEntitiesType = Any
SomeEntitiesType_types_tuple = (e.Entity,)

# (module where launch / launch_ros define the name, public name, tuilaunch's object)
NAMES: list[tuple[str, str, Any]] = [
    # launch, top level
    ("launch.action", "Action", e.Action),
    ("launch.condition", "Condition", c.Condition),
    ("launch.event", "Event", ev.Event),
    ("launch.event_handler", "EventHandler", e.EventHandler),
    ("launch.event_handler", "BaseEventHandler", e.EventHandler),
    ("launch.invalid_launch_file_error", "InvalidLaunchFileError", InvalidLaunchFileError),
    ("launch.launch_context", "LaunchContext", LaunchContext),
    ("launch.launch_description", "LaunchDescription", e.LaunchDescription),
    ("launch.launch_description_entity", "LaunchDescriptionEntity", e.Entity),
    ("launch.launch_description_source", "LaunchDescriptionSource", e.LaunchDescriptionSource),
    ("launch.launch_introspector", "LaunchIntrospector", UNSUPPORTED),
    ("launch.launch_service", "LaunchService", UNSUPPORTED),
    ("launch.some_entities_type", "SomeEntitiesType", SomeEntitiesType),
    ("launch.some_entities_type", "SomeEntitiesType_types_tuple", SomeEntitiesType_types_tuple),
    ("launch.some_substitutions_type", "SomeSubstitutionsType", SomeSubstitutionsType),
    ("launch.some_substitutions_type", "SomeSubstitutionsType_types_tuple",
     SomeSubstitutionsType_types_tuple),
    ("launch.substitution", "Substitution", s.Substitution),
    # launch.actions
    ("launch.actions.append_environment_variable", "AppendEnvironmentVariable",
     e.AppendEnvironmentVariable),
    ("launch.actions.declare_launch_argument", "DeclareLaunchArgument", e.DeclareLaunchArgument),
    ("launch.actions.emit_event", "EmitEvent", e.EmitEvent),
    ("launch.actions.execute_local", "ExecuteLocal", e.ExecuteLocal),
    ("launch.actions.execute_process", "ExecuteProcess", e.ExecuteProcess),
    ("launch.actions.group_action", "GroupAction", e.GroupAction),
    ("launch.actions.include_launch_description", "IncludeLaunchDescription",
     e.IncludeLaunchDescription),
    ("launch.actions.log_info", "LogInfo", e.LogInfo),
    ("launch.actions.opaque_coroutine", "OpaqueCoroutine", e.OpaqueCoroutine),
    ("launch.actions.opaque_function", "OpaqueFunction", e.OpaqueFunction),
    ("launch.actions.pop_environment", "PopEnvironment", e.PopEnvironment),
    ("launch.actions.pop_launch_configurations", "PopLaunchConfigurations",
     e.PopLaunchConfigurations),
    ("launch.actions.push_environment", "PushEnvironment", e.PushEnvironment),
    ("launch.actions.push_launch_configurations", "PushLaunchConfigurations",
     e.PushLaunchConfigurations),
    ("launch.actions.register_event_handler", "RegisterEventHandler", e.RegisterEventHandler),
    ("launch.actions.reset_environment", "ResetEnvironment", e.ResetEnvironment),
    ("launch.actions.reset_launch_configurations", "ResetLaunchConfigurations",
     e.ResetLaunchConfigurations),
    ("launch.actions.set_environment_variable", "SetEnvironmentVariable",
     e.SetEnvironmentVariable),
    ("launch.actions.set_launch_configuration", "SetLaunchConfiguration",
     e.SetLaunchConfiguration),
    ("launch.actions.shutdown_action", "Shutdown", e.Shutdown),
    ("launch.actions.timer_action", "TimerAction", e.TimerAction),
    ("launch.actions.unregister_event_handler", "UnregisterEventHandler", UNSUPPORTED),
    ("launch.actions.unset_environment_variable", "UnsetEnvironmentVariable",
     e.UnsetEnvironmentVariable),
    ("launch.actions.unset_launch_configuration", "UnsetLaunchConfiguration",
     e.UnsetLaunchConfiguration),
    # launch.conditions
    ("launch.conditions.evaluate_condition_expression_impl", "evaluate_condition_expression",
     c.evaluate_condition_expression),
    ("launch.conditions.evaluate_condition_expression_impl", "VALID_TRUE_EXPRESSIONS",
     ["true", "1"]),
    ("launch.conditions.evaluate_condition_expression_impl", "VALID_FALSE_EXPRESSIONS",
     ["false", "0"]),
    ("launch.conditions.if_condition", "IfCondition", c.IfCondition),
    ("launch.conditions.invalid_condition_expression_error", "InvalidConditionExpressionError",
     c.InvalidConditionExpressionError),
    ("launch.conditions.launch_configuration_equals", "LaunchConfigurationEquals",
     c.LaunchConfigurationEquals),
    ("launch.conditions.launch_configuration_not_equals", "LaunchConfigurationNotEquals",
     c.LaunchConfigurationNotEquals),
    ("launch.conditions.unless_condition", "UnlessCondition", c.UnlessCondition),
    # launch.descriptions
    ("launch.descriptions.executable", "Executable", e.Executable),
    # launch.event_handlers
    ("launch.event_handlers.event_named", "event_named", UNSUPPORTED),
    ("launch.event_handlers.on_action_event_base", "OnActionEventBase", e.EventHandler),
    ("launch.event_handlers.on_execution_complete", "OnExecutionComplete",
     e.OnExecutionComplete),
    ("launch.event_handlers.on_include_launch_description", "OnIncludeLaunchDescription",
     UNSUPPORTED),
    ("launch.event_handlers.on_process_exit", "OnProcessExit", e.OnProcessExit),
    ("launch.event_handlers.on_process_io", "OnProcessIO", e.OnProcessIO),
    ("launch.event_handlers.on_process_start", "OnProcessStart", e.OnProcessStart),
    ("launch.event_handlers.on_shutdown", "OnShutdown", e.OnShutdown),
    # launch.events
    ("launch.events.execution_complete", "ExecutionComplete", ev.ExecutionComplete),
    ("launch.events.include_launch_description", "IncludeLaunchDescription", UNSUPPORTED),
    ("launch.events.matchers", "matches_action", e.matches_action),
    ("launch.events.shutdown", "Shutdown", e.Shutdown),
    ("launch.events.timer_event", "TimerEvent", ev.TimerEvent),
    ("launch.events.process.process_exited", "ProcessExited", ev.ProcessExited),
    ("launch.events.process.process_io", "ProcessIO", ev.ProcessIO),
    ("launch.events.process.process_matchers", "matches_pid", UNSUPPORTED),
    ("launch.events.process.process_matchers", "matches_name", UNSUPPORTED),
    ("launch.events.process.process_matchers", "matches_executable", UNSUPPORTED),
    ("launch.events.process.process_started", "ProcessStarted", ev.ProcessStarted),
    ("launch.events.process.process_stderr", "ProcessStderr", ev.ProcessStderr),
    ("launch.events.process.process_stdin", "ProcessStdin", ev.ProcessStdin),
    ("launch.events.process.process_stdout", "ProcessStdout", ev.ProcessStdout),
    ("launch.events.process.process_targeted_event", "ProcessTargetedEvent",
     ev.ProcessTargetedEvent),
    ("launch.events.process.running_process_event", "RunningProcessEvent",
     ev.RunningProcessEvent),
    ("launch.events.process.shutdown_process", "ShutdownProcess", e.ShutdownProcess),
    ("launch.events.process.signal_process", "SignalProcess", e.SignalProcess),
    # launch.launch_description_sources
    ("launch.launch_description_sources.any_launch_description_source",
     "AnyLaunchDescriptionSource", e.AnyLaunchDescriptionSource),
    ("launch.launch_description_sources.python_launch_description_source",
     "PythonLaunchDescriptionSource", e.PythonLaunchDescriptionSource),
    ("launch.launch_description_sources", "FrontendLaunchDescriptionSource",
     e.LaunchDescriptionSource),
    ("launch.launch_description_sources.any_launch_file_utilities",
     "get_launch_description_from_any_launch_file", UNSUPPORTED),
    ("launch.launch_description_sources.python_launch_file_utilities",
     "get_launch_description_from_python_launch_file", UNSUPPORTED),
    ("launch.launch_description_sources.python_launch_file_utilities",
     "load_python_launch_file_as_module", UNSUPPORTED),
    ("launch.launch_description_sources.python_launch_file_utilities",
     "InvalidPythonLaunchFileError", InvalidLaunchFileError),
    # launch.logging
    ("launch.logging", "get_logger", _get_logger),
    ("launch.logging", "get_output_loggers", UNSUPPORTED),
    ("launch.logging", "reset", UNSUPPORTED),
    # launch.substitutions
    ("launch.substitutions.anon_name", "AnonName", s.AnonName),
    ("launch.substitutions.boolean_substitution", "NotSubstitution", ls.NotSubstitution),
    ("launch.substitutions.boolean_substitution", "AndSubstitution", ls.AndSubstitution),
    ("launch.substitutions.boolean_substitution", "OrSubstitution", ls.OrSubstitution),
    ("launch.substitutions.boolean_substitution", "AnySubstitution", ls.AnySubstitution),
    ("launch.substitutions.boolean_substitution", "AllSubstitution", ls.AllSubstitution),
    ("launch.substitutions.command", "Command", s.Command),
    ("launch.substitutions.environment_variable", "EnvironmentVariable", s.EnvironmentVariable),
    ("launch.substitutions.equals_substitution", "EqualsSubstitution", ls.EqualsSubstitution),
    ("launch.substitutions.file_content", "FileContent", s.FileContent),
    ("launch.substitutions.find_executable", "FindExecutable", s.FindExecutable),
    ("launch.substitutions.if_else_substitution", "IfElseSubstitution", ls.IfElseSubstitution),
    ("launch.substitutions.launch_configuration", "LaunchConfiguration", s.LaunchConfiguration),
    ("launch.substitutions.launch_log_dir", "LaunchLogDir", s.LaunchLogDir),
    ("launch.substitutions.local_substitution", "LocalSubstitution", s.LocalSubstitution),
    ("launch.substitutions.not_equals_substitution", "NotEqualsSubstitution",
     ls.NotEqualsSubstitution),
    ("launch.substitutions.path_join_substitution", "PathJoinSubstitution",
     s.PathJoinSubstitution),
    ("launch.substitutions.path_join_substitution", "PathSubstitution", s.PathSubstitution),
    ("launch.substitutions.python_expression", "PythonExpression", s.PythonExpression),
    ("launch.substitutions.substitution_failure", "SubstitutionFailure", s.SubstitutionFailure),
    ("launch.substitutions.text_substitution", "TextSubstitution", s.TextSubstitution),
    ("launch.substitutions.this_launch_file", "ThisLaunchFile", s.ThisLaunchFile),
    ("launch.substitutions.this_launch_file_dir", "ThisLaunchFileDir", s.ThisLaunchFileDir),
    # launch.utilities
    ("launch.utilities.class_tools_impl", "is_a", u.is_a),
    ("launch.utilities.class_tools_impl", "is_a_subclass", u.is_a_subclass),
    ("launch.utilities.class_tools_impl", "isclassinstance", u.isclassinstance),
    ("launch.utilities.ensure_argument_type_impl", "ensure_argument_type",
     u.ensure_argument_type),
    ("launch.utilities.normalize_to_list_of_entities_impl", "normalize_to_list_of_entities",
     u.normalize_to_list_of_entities),
    ("launch.utilities.normalize_to_list_of_substitutions_impl",
     "normalize_to_list_of_substitutions", u.normalize_to_list_of_substitutions),
    ("launch.utilities.perform_substitutions_impl", "perform_substitutions",
     u.perform_substitutions),
    ("launch.utilities.signal_management", "AsyncSafeSignalManager", UNSUPPORTED),
    ("launch.utilities.visit_all_entities_and_collect_futures_impl",
     "visit_all_entities_and_collect_futures", UNSUPPORTED),
    ("launch.utilities.type_utils", "is_substitution", u.is_substitution),
    ("launch.utilities.type_utils", "normalize_typed_substitution",
     u.normalize_typed_substitution),
    ("launch.utilities.type_utils", "perform_typed_substitution", u.perform_typed_substitution),
    ("launch.utilities.type_utils", "coerce_to_type", u.coerce_to_type),
    ("launch.utilities.type_utils", "get_typed_value", u.get_typed_value),
    ("launch.utilities.typing_file_path", "FilePath", Any),
    # launch_ros.actions
    ("launch_ros.actions.composable_node_container", "ComposableNodeContainer",
     e.ComposableNodeContainer),
    ("launch_ros.actions.load_composable_nodes", "LoadComposableNodes", e.LoadComposableNodes),
    ("launch_ros.actions.node", "Node", e.Node),
    ("launch_ros.actions.push_ros_namespace", "PushROSNamespace", e.PushROSNamespace),
    ("launch_ros.actions.push_ros_namespace", "PushRosNamespace", e.PushRosNamespace),
    ("launch_ros.actions.ros_timer", "ROSTimer", e.TimerAction),
    ("launch_ros.actions.ros_timer", "RosTimer", e.TimerAction),
    ("launch_ros.actions.set_parameter", "SetParameter", e.SetParameter),
    ("launch_ros.actions.set_parameters_from_file", "SetParametersFromFile",
     e.SetParametersFromFile),
    ("launch_ros.actions.set_remap", "SetRemap", e.SetRemap),
    ("launch_ros.actions.set_ros_log_dir", "SetROSLogDir", e.SetROSLogDir),
    ("launch_ros.actions.set_use_sim_time", "SetUseSimTime", e.SetUseSimTime),
    # launch_ros.descriptions and parameter_descriptions
    ("launch_ros.descriptions.composable_node", "ComposableNode", e.ComposableNode),
    ("launch_ros.descriptions", "Parameter", pf.Parameter),
    ("launch_ros.descriptions", "ParameterFile", pf.ParameterFile),
    ("launch_ros.descriptions", "ParameterValue", params.ParameterValue),
    ("launch_ros.parameter_descriptions", "Parameter", pf.Parameter),
    ("launch_ros.parameter_descriptions", "ParameterFile", pf.ParameterFile),
    ("launch_ros.parameter_descriptions", "ParameterValue", params.ParameterValue),
    ("launch_ros.parameters_type", "SomeParameters", Any),
    ("launch_ros.parameters_type", "SomeParameterFile", Any),
    ("launch_ros.parameters_type", "SomeParameterValue", Any),
    ("launch_ros.parameters_type", "SomeParametersDict", Any),
    ("launch_ros.parameters_type", "Parameters", Any),
    ("launch_ros.remap_rule_type", "SomeRemapRules", Any),
    ("launch_ros.remap_rule_type", "SomeRemapRule", Any),
    ("launch_ros.remap_rule_type", "RemapRules", Any),
    # launch_ros lifecycle actions and events: describe/lifecycle.py's COMPAT_ROWS
    ("launch_ros.ros_adapters", "get_ros_node", UNSUPPORTED),
    ("launch_ros.ros_adapters", "get_ros_adapter", UNSUPPORTED),
    # launch_ros.substitutions
    ("launch_ros.substitutions.executable_in_package", "ExecutableInPackage",
     rs.ExecutableInPackage),
    ("launch_ros.substitutions.find_package", "FindPackage", rs.FindPackagePrefix),
    ("launch_ros.substitutions.find_package", "FindPackagePrefix", rs.FindPackagePrefix),
    ("launch_ros.substitutions.find_package", "FindPackageShare", rs.FindPackageShare),
    ("launch_ros.substitutions.parameter", "Parameter", rs.ParameterSubstitution),
    # launch_ros.utilities
    ("launch_ros.utilities.namespace_utils", "is_root_namespace", u.is_root_namespace),
    ("launch_ros.utilities.namespace_utils", "is_namespace_absolute", u.is_namespace_absolute),
    ("launch_ros.utilities.namespace_utils", "make_namespace_absolute",
     u.make_namespace_absolute),
    ("launch_ros.utilities.namespace_utils", "prefix_namespace", u.prefix_namespace),
    ("launch_ros.utilities.normalize_remap_rule", "normalize_remap_rules",
     u.normalize_remap_rules),
    ("launch_ros.utilities.normalize_parameters", "normalize_parameters", UNSUPPORTED),
    ("launch_ros.utilities.evaluate_parameters", "evaluate_parameters", UNSUPPORTED),
    ("launch_ros.utilities.to_parameters_list", "to_parameters_list", UNSUPPORTED),
    ("launch_ros.utilities.track_node_names", "add_node_name", u.add_node_name),
    ("launch_ros.utilities.track_node_names", "get_node_name_count", u.get_node_name_count),
    # XML and YAML files are read by their extension, whatever source class names them
    ("launch_xml.launch_description_sources.xml_launch_description_source",
     "XMLLaunchDescriptionSource", e.LaunchDescriptionSource),
    ("launch_yaml.launch_description_sources.yaml_launch_description_source",
     "YAMLLaunchDescriptionSource", e.LaunchDescriptionSource),
    # simple_launch
    ("simple_launch.simple_launcher", "SimpleLauncher", SimpleLauncher),
    ("simple_launch.simple_substitution", "SimpleSubstitution", s.SimpleSubstitution),
    ("simple_launch.simple_substitution", "flatten", s.flatten),
]

# the module files holding only one class in the real packages, named as launch names them
_SIMPLE_EVENTS = ("When", "OnProcessStart", "OnProcessExit", "OnProcessIO",
                  "OnExecutionComplete", "OnShutdown")

_extra: list[tuple[str, str, Any]] = []


def register(module: str, name: str, obj: Any) -> None:
    """Adds (or replaces) one public name; for modules of the engine outside this one."""
    _extra.append((module, name, obj))


def _rows() -> list[tuple[str, str, Any]]:
    from .. import events as simple_events
    from . import gazebo

    rows = list(NAMES)
    rows += [("simple_launch.events", name, getattr(simple_events, name))
             for name in _SIMPLE_EVENTS]
    rows += [("simple_launch.gazebo", name, getattr(gazebo, name))
             for name in ("GazeboBridge", "ros_gz_prefix", "only_show_args")]
    from ..lifecycle import COMPAT_ROWS as lifecycle_rows

    return rows + lifecycle_rows + _extra


class CompatModule(ModuleType):
    """A module of the tree: a missing public name says tuilaunch lacks it, not to install."""

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        raise AttributeError(unsupported_message(f"{self.__name__}.{name}"))


def unsupported_message(dotted: str) -> str:
    return f"tuilaunch does not support {dotted} yet"


def build_modules() -> dict[str, ModuleType]:
    """Every module of the tree, fresh, with its parents' attributes wired."""
    modules: dict[str, ModuleType] = {}

    def module(name: str) -> ModuleType:
        if name not in modules:
            modules[name] = CompatModule(name)
            modules[name].__dict__["__path__"] = []  # a package: submodules may be imported
            modules[name].__dict__["__all__"] = []
            if "." in name:
                parent, child = name.rsplit(".", 1)
                setattr(module(parent), child, modules[name])
        return modules[name]

    unsupported: dict[str, set[str]] = {}
    for where, name, obj in _rows():
        homes = [where]
        if "." in where:
            homes.append(where.rsplit(".", 1)[0])  # packages offer their submodules' names
        for home in homes:
            mod = module(home)
            if obj is UNSUPPORTED:
                unsupported.setdefault(home, set()).add(name)
                mod.__dict__.pop(name, None)
            else:
                setattr(mod, name, obj)
                mod.__dict__["__all__"].append(name)
    for home, names in unsupported.items():
        modules[home].__dict__["_unsupported"] = names
    return modules
