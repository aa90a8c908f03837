"""`launch`, `launch_ros` and `simple_launch` as packages with launch's module tree.

While a launch file loads, `import launch.substitutions.command`, `from launch.utilities
import perform_substitutions` or `launch.SomeSubstitutionsType` must work as with ROS's own
packages, because third-party extensions (nav2_common, ros2_control helpers) import from
where launch defines each name. The tree is built from NAMES, one row per public name at the
module that defines it: a package also offers every name of its direct submodules, as launch's
`__init__` files do. A name launch has and tuilaunch does not is listed as UNSUPPORTED, so a
file using it fails with "tuilaunch does not support launch.actions.X yet".

Other modules of the engine may add names of their own with `register(...)`.
"""

from __future__ import annotations

import logging
import re
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

def named_after(package: str, *objects: Any) -> list[tuple[str, str, Any]]:
    """Rows of classes that launch defines each in a module named after it, its convention
    (launch.actions.LogInfo in launch/actions/log_info.py), where tuilaunch's class has
    launch's name."""
    return [(f"{package}.{re.sub(r'(?<!^)(?=[A-Z])', '_', obj.__name__).lower()}",
             obj.__name__, obj) for obj in objects]


# (module where launch / launch_ros define the name, public name, tuilaunch's object)
NAMES: list[tuple[str, str, Any]] = [
    # launch, top level
    *named_after("launch", c.Condition, ev.Event, e.EventHandler, InvalidLaunchFileError,
                 LaunchContext, e.LaunchDescription, e.LaunchDescriptionSource, s.Substitution),
    ("launch.action", "Action", e.Action),
    ("launch.event_handler", "BaseEventHandler", e.EventHandler),
    ("launch.launch_description_entity", "LaunchDescriptionEntity", e.Entity),
    ("launch.launch_introspector", "LaunchIntrospector", UNSUPPORTED),
    ("launch.launch_service", "LaunchService", UNSUPPORTED),
    ("launch.some_entities_type", "SomeEntitiesType", SomeEntitiesType),
    ("launch.some_entities_type", "SomeEntitiesType_types_tuple", SomeEntitiesType_types_tuple),
    ("launch.some_substitutions_type", "SomeSubstitutionsType", SomeSubstitutionsType),
    ("launch.some_substitutions_type", "SomeSubstitutionsType_types_tuple",
     SomeSubstitutionsType_types_tuple),
    # launch.actions
    *named_after("launch.actions", e.AppendEnvironmentVariable, e.DeclareLaunchArgument,
                 e.EmitEvent, e.ExecuteLocal, e.ExecuteProcess, e.GroupAction,
                 e.IncludeLaunchDescription, e.LogInfo, e.OpaqueCoroutine, e.OpaqueFunction,
                 e.PopEnvironment, e.PopLaunchConfigurations, e.PushEnvironment,
                 e.PushLaunchConfigurations, e.RegisterEventHandler, e.ResetEnvironment,
                 e.ResetLaunchConfigurations, e.SetEnvironmentVariable, e.SetLaunchConfiguration,
                 e.TimerAction, e.UnsetEnvironmentVariable, e.UnsetLaunchConfiguration),
    ("launch.actions.shutdown_action", "Shutdown", e.Shutdown),
    ("launch.actions.unregister_event_handler", "UnregisterEventHandler", UNSUPPORTED),
    # launch.conditions
    *named_after("launch.conditions", c.IfCondition, c.InvalidConditionExpressionError,
                 c.LaunchConfigurationEquals, c.LaunchConfigurationNotEquals, c.UnlessCondition),
    ("launch.conditions.evaluate_condition_expression_impl", "evaluate_condition_expression",
     c.evaluate_condition_expression),
    ("launch.conditions.evaluate_condition_expression_impl", "VALID_TRUE_EXPRESSIONS",
     ["true", "1"]),
    ("launch.conditions.evaluate_condition_expression_impl", "VALID_FALSE_EXPRESSIONS",
     ["false", "0"]),
    # launch.descriptions
    *named_after("launch.descriptions", e.Executable),
    # launch.event_handlers
    *named_after("launch.event_handlers", e.OnExecutionComplete, e.OnProcessExit, e.OnProcessStart,
                 e.OnShutdown),
    ("launch.event_handlers.event_named", "event_named", UNSUPPORTED),
    ("launch.event_handlers.on_action_event_base", "OnActionEventBase", e.EventHandler),
    ("launch.event_handlers.on_include_launch_description", "OnIncludeLaunchDescription",
     UNSUPPORTED),
    ("launch.event_handlers.on_process_io", "OnProcessIO", e.OnProcessIO),
    # launch.events
    *named_after("launch.events", ev.ExecutionComplete, e.Shutdown, ev.TimerEvent),
    *named_after("launch.events.process", ev.ProcessExited, ev.ProcessStarted, ev.ProcessStderr,
                 ev.ProcessStdin, ev.ProcessStdout, ev.ProcessTargetedEvent, ev.RunningProcessEvent,
                 e.ShutdownProcess, e.SignalProcess),
    ("launch.events.include_launch_description", "IncludeLaunchDescription", UNSUPPORTED),
    ("launch.events.matchers", "matches_action", e.matches_action),
    ("launch.events.process.process_io", "ProcessIO", ev.ProcessIO),
    ("launch.events.process.process_matchers", "matches_pid", UNSUPPORTED),
    ("launch.events.process.process_matchers", "matches_name", UNSUPPORTED),
    ("launch.events.process.process_matchers", "matches_executable", UNSUPPORTED),
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
    *named_after("launch.substitutions", s.AnonName, s.Command, s.EnvironmentVariable,
                 ls.EqualsSubstitution, s.FileContent, s.FindExecutable, ls.IfElseSubstitution,
                 s.LaunchConfiguration, s.LaunchLogDir, s.LocalSubstitution,
                 ls.NotEqualsSubstitution, s.PythonExpression, s.SubstitutionFailure,
                 s.TextSubstitution, s.ThisLaunchFile, s.ThisLaunchFileDir),
    ("launch.substitutions.boolean_substitution", "NotSubstitution", ls.NotSubstitution),
    ("launch.substitutions.boolean_substitution", "AndSubstitution", ls.AndSubstitution),
    ("launch.substitutions.boolean_substitution", "OrSubstitution", ls.OrSubstitution),
    ("launch.substitutions.boolean_substitution", "AnySubstitution", ls.AnySubstitution),
    ("launch.substitutions.boolean_substitution", "AllSubstitution", ls.AllSubstitution),
    ("launch.substitutions.path_join_substitution", "PathJoinSubstitution",
     s.PathJoinSubstitution),
    ("launch.substitutions.path_join_substitution", "PathSubstitution", s.PathSubstitution),
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
    *named_after("launch_ros.actions", e.ComposableNodeContainer, e.LoadComposableNodes, e.Node,
                 e.PushRosNamespace, e.SetParameter, e.SetParametersFromFile, e.SetRemap,
                 e.SetUseSimTime),
    ("launch_ros.actions.push_ros_namespace", "PushROSNamespace", e.PushROSNamespace),
    ("launch_ros.actions.ros_timer", "ROSTimer", e.TimerAction),
    ("launch_ros.actions.ros_timer", "RosTimer", e.TimerAction),
    ("launch_ros.actions.set_ros_log_dir", "SetROSLogDir", e.SetROSLogDir),
    # launch_ros.descriptions and parameter_descriptions
    *named_after("launch_ros.descriptions", e.ComposableNode),
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
    # launch_ros lifecycle actions and events: _rows() (describe/lifecycle.py, loaded late)
    ("launch_ros.ros_adapters", "get_ros_node", UNSUPPORTED),
    ("launch_ros.ros_adapters", "get_ros_adapter", UNSUPPORTED),
    # launch_ros.substitutions
    *named_after("launch_ros.substitutions", rs.ExecutableInPackage),
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
    *named_after("simple_launch", SimpleLauncher, s.SimpleSubstitution),
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
    from .. import lifecycle as lc

    rows += [*named_after("launch_ros.actions", lc.LifecycleNode, lc.LifecycleTransition),
             *named_after("launch_ros.events.lifecycle", lc.ChangeState, lc.StateTransition),
             *named_after("launch_ros.event_handlers", lc.OnStateTransition)]
    rows += [(where, "matches_node_name", lc.matches_node_name) for where in (
        "launch_ros.events.lifecycle.lifecycle_node_matchers",
        "launch_ros.events.matchers.matches_node_name", "launch_ros.events")]
    return rows + _extra


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
