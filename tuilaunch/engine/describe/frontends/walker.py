"""Map the tags of an XML or YAML launch file onto the engine's entities (one method per tag).

Each tag reads the attributes its launch / launch_ros `parse` method reads, with the same
types, so a file means here what it means to `ros2 launch`. Every entity remembers the line
of its tag; every error names the file, line, column, tag and attribute at fault.
"""

from __future__ import annotations

import difflib
import importlib
import os
from collections.abc import Callable
from typing import Any

from ...errors import LaunchError
from .. import entities as ent
from ..conditions import Condition, IfCondition, UnlessCondition
from ..substitutions import Substitution, TextSubstitution
from ..type_utils import check_identifier, coerce_text, type_name
from ..values import ParameterValue
from .attribute_values import command_line, pairs, parse, text, typed
from .element import Element
from .extra_substitutions import (
    AppendedEnvironment,
    SubstitutedParameterFile,
    default_path_separator,
)


class Unsupported(ent.Entity):
    """A launch tag tuilaunch does not perform: kept so the plan warns where it is."""

    def __init__(self, tag: str, why: str) -> None:
        self._init_entity(None)
        self.tag = tag
        self.why = why

    def __repr__(self) -> str:
        return f"<{self.tag}> ({self.why})"

    def describe(self) -> str:
        return f"<{self.tag}>"


_PUSH_NAMESPACE = ("a group takes no namespace in ros2 launch: put "
                   '<push_ros_namespace namespace="..."/> first inside the group')
_NODE_NAMESPACE = "did you mean namespace? ns is ROS 1's spelling"
# Attributes ros2 launch refuses that people bring from ROS 1 launch files, with what to
# write instead: the closest attribute by spelling would mislead here.
_REFUSED_ATTRIBUTES: dict[str, dict[str, str]] = {
    "group": {"ns": _PUSH_NAMESPACE, "namespace": _PUSH_NAMESPACE},
    **{tag: {"ns": _NODE_NAMESPACE}
       for tag in ("node", "lifecycle_node", "node_container")},
}


def _lifecycle_class() -> type[ent.Node] | None:
    """launch_ros's LifecycleNode when the engine has it (describe.lifecycle)."""
    try:
        module = importlib.import_module("..lifecycle", __package__)
    except ImportError:
        return None
    found = getattr(module, "LifecycleNode", None)
    return found if isinstance(found, type) and issubclass(found, ent.Node) else None


class Walker:
    """Builds the entities of one file."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.handlers: dict[str, Callable[[Element], list[Any]]] = {
            "arg": self.arg, "let": self.let, "include": self.include, "group": self.group,
            "push-ros-namespace": self.push_ros_namespace,
            "push_ros_namespace": self.push_ros_namespace,
            "node": self.node, "executable": self.executable,
            "set_env": self.set_env, "unset_env": self.unset_env,
            "append_env": self.append_env,
            "set_parameter": self.set_parameter, "set_remap": self.set_remap,
            "set_use_sim_time": self.set_use_sim_time,
            "timer": self.timer, "ros_timer": self.timer, "log": self.log,
            "shutdown": self.shutdown, "node_container": self.node_container,
            "load_composable_node": self.load_composable_node,
            "lifecycle_node": self.lifecycle_node,
            "reset": self.reset, "reset_env": self.reset_env,
            "set_parameters_from_file": self.set_parameters_from_file,
            "set_ros_log_dir": self.unsupported,
        }

    # --- structure ----------------------------------------------------------------------

    def description(self, root: Element) -> list[Any]:
        deprecated = root.get("deprecated", optional=True)
        for name in root.attribute_names():
            root.mark_read(name)  # launch reads none of the root's attributes but `deprecated`
        actions = self.actions(root.children())
        if deprecated is not None:
            notice = ent.LogInfo(msg=f"{os.path.basename(self.path)} is deprecated: "
                                 f"{deprecated}")
            notice.origin = root.line_origin
            actions.insert(0, notice)
        return actions

    def actions(self, elements: list[Element]) -> list[Any]:
        out: list[Any] = []
        for element in elements:
            out.extend(self.action(element))
        return out

    def action(self, element: Element) -> list[Any]:
        handler = self.handlers.get(element.tag)
        if handler is None:
            close = difflib.get_close_matches(element.tag, self.handlers, 1)
            if close:
                raise element.error(f"unknown tag (did you mean <{close[0]}>?)",
                                    hint="known tags: " + ", ".join(sorted(self.handlers)))
            raise element.error(
                "unknown tag: not a launch or launch_ros action (a third-party launch "
                "extension?); tuilaunch cannot run it",
                hint="known tags: " + ", ".join(sorted(self.handlers)))
        condition = self.condition(element)
        try:
            made = handler(element)
        except LaunchError as exc:
            if exc.origin is not None and exc.origin.file == element.origin.file:
                raise
            # raised by an entity's constructor: point at the tag, not at our code
            raise element.error(exc.message, hint=exc.hint) from None
        except (TypeError, ValueError, AttributeError, KeyError) as exc:
            # a shape no check above foresaw: still one line naming the tag
            raise element.error(f"cannot read this tag: {type(exc).__name__}: {exc}") from None
        element.check_complete(_REFUSED_ATTRIBUTES.get(element.tag))
        for entity in made:
            # an on_exit handler shares its process's condition, or it would wait forever
            entity.condition = condition
            entity.origin = element.line_origin
        return made

    def condition(self, element: Element) -> Condition | None:
        if_text = element.get("if", optional=True)
        unless_text = element.get("unless", optional=True)
        if if_text is not None and unless_text is not None:
            raise element.error("'if' and 'unless' cannot be used together", at="unless")
        condition: Condition | None = None
        if if_text is not None:
            condition = IfCondition(parse(element, "if", if_text))
        elif unless_text is not None:
            condition = UnlessCondition(parse(element, "unless", unless_text))
        if condition is not None:
            condition.origin = element.position_of("if" if if_text is not None else "unless")
        return condition

    # --- launch actions -------------------------------------------------------------------

    def arg(self, element: Element) -> list[Any]:
        name = element.get("name")
        if not name:
            raise element.error("attribute 'name' is empty", at="name")
        choices = element.nested("choice")
        choice_values = None
        if choices is not None:
            choice_values = [str(c.get("value")) for c in choices]
            for choice in choices:
                choice.check_complete()
        default = text(element, "default", optional=True)
        if choice_values and isinstance(default, str) and default not in choice_values:
            raise element.error(f"default {default!r} is not one of the choices: "
                                f"{', '.join(choice_values)}", at="default")
        return [ent.DeclareLaunchArgument(
            str(name), default_value=default,
            description=element.get("description", optional=True), choices=choice_values,
            py_type=_form_type(default))]

    def let(self, element: Element) -> list[Any]:
        return [ent.SetLaunchConfiguration(text(element, "name"),
                                           text(element, "value"))]

    def include(self, element: Element) -> list[Any]:
        return [ent.IncludeLaunchDescription(
            text(element, "file"),
            launch_arguments=pairs(element, "arg", "name", "value"))]

    def group(self, element: Element) -> list[Any]:
        scoped = element.get("scoped", "bool", optional=True)
        forwarding = element.get("forwarding", "bool", optional=True)
        keep = pairs(element, "keep", "name", "value")
        children = [c for c in element.children() if c.tag != "keep"]
        group = ent.Group(self.actions(children),
                          scoped=True if scoped is None else bool(scoped),
                          launch_configurations=dict(keep or []))
        group.forwarding = forwarding is not False
        return [group]

    def push_ros_namespace(self, element: Element) -> list[Any]:
        return [ent.PushRosNamespace(text(element, "namespace"))]

    def set_env(self, element: Element) -> list[Any]:
        return [ent.SetEnvironmentVariable(text(element, "name"),
                                           text(element, "value"))]

    def unset_env(self, element: Element) -> list[Any]:
        return [ent.UnsetEnvironmentVariable(text(element, "name"))]

    def append_env(self, element: Element) -> list[Any]:
        name = text(element, "name")
        prepend = typed(element, "prepend", "bool")
        separator = text(element, "separator", optional=True)
        value = AppendedEnvironment(name, text(element, "value"),
                                    "false" if prepend is None else str(prepend).lower(),
                                    default_path_separator() if separator is None
                                    else separator)
        value.origin = element.origin
        return [ent.SetEnvironmentVariable(name, value)]

    def timer(self, element: Element) -> list[Any]:
        period = typed(element, "period", "float")
        if period is None:
            raise element.error("attribute 'period' is required", hint="period=\"2.0\" (s)")
        element.get("cancel_on_shutdown", "bool", optional=True, can_be_str=True)
        return [ent.TimerAction(period=period, actions=self.actions(element.children()))]

    def log(self, element: Element) -> list[Any]:
        return [ent.LogInfo(msg=text(element, "message"))]

    def shutdown(self, element: Element) -> list[Any]:
        reason = text(element, "reason", optional=True)
        return [ent.Shutdown(reason="reason not given" if not reason else reason)]

    def reset(self, element: Element) -> list[Any]:
        keep = pairs(element, "keep", "name", "value")
        return [ent.ResetLaunchConfigurations(dict(keep or []))]

    def reset_env(self, element: Element) -> list[Any]:
        return [ent.ResetEnvironment()]

    def unsupported(self, element: Element) -> list[Any]:
        for name in element.attribute_names():
            element.mark_read(name)
        element.children()
        return [Unsupported(element.tag, "a launch action")]

    # --- launch_ros actions ---------------------------------------------------------------

    def set_parameter(self, element: Element) -> list[Any]:
        return [ent.SetParameter(text(element, "name"),
                                 _yaml_typed(text(element, "value")))]

    def set_parameters_from_file(self, element: Element) -> list[Any]:
        return [ent.SetParametersFromFile(text(element, "filename"))]

    def set_use_sim_time(self, element: Element) -> list[Any]:
        return [ent.SetParameter("use_sim_time", _yaml_typed(text(element, "value")))]

    def set_remap(self, element: Element) -> list[Any]:
        return [ent.SetRemap(text(element, "from"), text(element, "to"))]

    def executable(self, element: Element) -> list[Any]:
        cmd = command_line(element, "cmd", str(element.get("cmd")))
        kwargs = self.process_arguments(element)
        kwargs["name"] = text(element, "name", optional=True)
        shell = element.get("shell", "bool", optional=True)
        process = ent.ExecuteProcess(cmd=cmd, shell=bool(shell), **kwargs)
        return [process, *self.on_exit(element, process)]

    def process_arguments(self, element: Element) -> dict[str, Any]:
        """What launch's ExecuteProcess.parse reads, for executables and nodes alike."""
        kwargs: dict[str, Any] = {}
        for attribute, keyword in (("cwd", "cwd"), ("launch-prefix", "prefix"),
                                   ("output", "output"), ("respawn", "respawn")):
            value = text(element, attribute, optional=True)
            if value is not None:
                kwargs[keyword] = value
        for attribute in ("respawn_delay", "sigterm_timeout", "sigkill_timeout"):
            number = element.get(attribute, "float", optional=True)
            if number is not None:
                if number < 0:
                    raise element.error(f"attribute '{attribute}' must not be negative",
                                        at=attribute)
                kwargs[attribute] = number
        retries = element.get("respawn_max_retries", "int", optional=True)
        if retries is not None:
            kwargs["respawn_max_retries"] = retries
        element.get("emulate_tty", "bool", optional=True)
        env = pairs(element, "env", "name", "value")
        if env is not None:
            kwargs["additional_env"] = dict(env)
        return kwargs

    def on_exit(self, element: Element, process: ent.Entity) -> list[Any]:
        action = element.get("on_exit", optional=True)
        if action is None:
            return []
        if action != "shutdown":
            raise element.error(f"on_exit={action!r}: only on_exit=\"shutdown\" exists",
                                at="on_exit")
        # launch's parser gives `[Shutdown()]`: its reason is launch's default
        handler = ent.OnProcessExit(target_action=process, on_exit=[ent.Shutdown()])
        return [ent.RegisterEventHandler(handler)]

    def node_arguments(self, element: Element) -> dict[str, Any]:
        kwargs = self.process_arguments(element)
        if element.has("shell"):
            element.get("shell", "bool")
        for attribute, keyword in (("args", "arguments"), ("ros_args", "ros_arguments")):
            raw = element.get(attribute, optional=True)
            if raw is not None:
                kwargs[keyword] = command_line(element, attribute, str(raw))
        name = text(element, "name", optional=True)
        if name is None:
            name = text(element, "node-name", optional=True)
        kwargs["name"] = name
        kwargs["exec_name"] = text(element, "exec_name", optional=True)
        kwargs["package"] = text(element, "pkg", optional=True)
        kwargs["executable"] = text(element, "exec")
        kwargs["namespace"] = text(element, "namespace", optional=True)
        kwargs["remappings"] = pairs(element, "remap", "from", "to")
        kwargs["parameters"] = self.parameters(element)
        return kwargs

    def node(self, element: Element) -> list[Any]:
        node = ent.Node(**self.node_arguments(element))
        return [node, *self.on_exit(element, node)]

    def lifecycle_node(self, element: Element) -> list[Any]:
        kwargs = self.node_arguments(element)
        autostart = typed(element, "autostart", "bool")
        lifecycle = _lifecycle_class()
        if lifecycle is None:
            node = ent.Node(**kwargs)  # no lifecycle support in this engine: a plain node
        else:
            if autostart is not None:
                kwargs["autostart"] = autostart
            node = lifecycle(**kwargs)
        return [node, *self.on_exit(element, node)]

    def node_container(self, element: Element) -> list[Any]:
        kwargs = self.node_arguments(element)
        if kwargs.get("name") is None or kwargs.get("namespace") is None:
            raise element.error("a node container needs 'name' and 'namespace'",
                                hint="namespace=\"\" keeps the current namespace")
        components = self.components(element)
        container = ent.ComposableNodeContainer(composable_node_descriptions=components,
                                                **kwargs)
        return [container, *self.on_exit(element, container)]

    def load_composable_node(self, element: Element) -> list[Any]:
        target = text(element, "target")
        components = self.components(element)
        if not components:
            raise element.error("needs at least one <composable_node>")
        return [ent.LoadComposableNodes(composable_node_descriptions=components,
                                        target_container=target)]

    def components(self, element: Element) -> list[ent.ComposableNode]:
        """`<composable_node>`s and (newer launch_ros) `<composable_lifecycle_node>`s."""
        nested = [*(element.nested("composable_node") or []),
                  *(element.nested("composable_lifecycle_node") or [])]
        nested.sort(key=lambda e: (e.origin.line, e.origin.column or 0))
        return [self.composable_node(c) for c in nested]

    def composable_node(self, element: Element) -> ent.ComposableNode:
        condition = self.condition(element)
        if element.tag == "composable_lifecycle_node":
            element.get("autostart", "bool", optional=True, can_be_str=True)
        extra = pairs(element, "extra_arg", "name", "value")
        component = ent.ComposableNode(
            package=text(element, "pkg"), plugin=text(element, "plugin"),
            name=text(element, "name"),
            namespace=text(element, "namespace", optional=True),
            parameters=self.parameters(element),
            remappings=pairs(element, "remap", "from", "to"),
            # launch_ros reads <extra_arg value=> as YAML, like a parameter: "true" is a bool
            extra_arguments=[{k: v if isinstance(v, Substitution) else TextSubstitution(str(v))}
                             for k, v in extra] if extra else None,
            condition=condition)
        component.origin = element.line_origin
        element.check_complete()
        return component

    # --- parameters -----------------------------------------------------------------------

    def parameters(self, element: Element) -> list[Any] | None:
        """`<param name= value=>`, nested `<param>`s and `<param from="file.yaml"/>`, in order."""
        nested = element.nested("param")
        if nested is None:
            return None
        out: list[Any] = []
        for param in nested:
            if param.has("from"):
                if param.has("name"):
                    raise param.error("'name' and 'from' cannot be used together")
                allow = typed(param, "allow_substs", "bool")
                path = text(param, "from")
                if allow is not None and allow is not False:
                    path = SubstitutedParameterFile(path, str(allow).lower()
                                                    if isinstance(allow, bool) else allow)
                    path.origin = param.origin
                out.append(path)
                param.check_complete()
            elif param.has("name"):
                out.append(self.parameter_dict([param]))
            else:
                raise param.error("needs a 'name' (with a value or nested <param>s) or "
                                  "'from' (a YAML file)")
        return out

    def parameter_dict(self, params: list[Element]) -> dict[Any, Any]:
        out: dict[Any, Any] = {}
        for param in params:
            name = text(param, "name")
            identifier = param.get("type", optional=True)
            spec = "yaml"
            if identifier is not None:
                try:
                    spec = check_identifier(str(identifier))
                except ValueError as exc:
                    raise param.error(str(exc), at="type") from None
            value = param.get("value", spec, optional=True)
            children = param.nested("param")
            param.check_complete()
            if value is not None and children:
                raise param.error("'value' and nested <param>s cannot be used together")
            if children:
                if identifier is not None:
                    raise param.error("'type' and nested <param>s cannot be used together")
                out[name] = self.parameter_dict(children)
            elif value is not None:
                parsed = parse(param, "value", value)
                if isinstance(parsed, list) and any(isinstance(v, Substitution) for v in parsed):
                    # a `value-sep` list: every item is its own value, typed on its own
                    parsed = [v if isinstance(v, Substitution) else TextSubstitution(str(v))
                              if isinstance(v, str) else v for v in parsed]
                lazy = isinstance(parsed, Substitution) or (
                    isinstance(parsed, list) and any(isinstance(v, Substitution)
                                                     for v in parsed))
                if identifier is not None and not lazy and spec != "str":
                    parsed = self.coerced(param, parsed, spec)
                out[name] = ParameterValue(parsed, value_type=spec) \
                    if lazy and identifier is not None else parsed
            else:
                raise param.error("needs a 'value' or nested <param>s")
        return out


    @staticmethod
    def coerced(param: Element, value: Any, spec: str) -> Any:
        """A typed value written as text (YAML quotes, or XML text that did not fit)."""
        try:
            if isinstance(value, str):
                return coerce_text(value, spec)
            if isinstance(value, list) and all(isinstance(v, str) for v in value):
                return [coerce_text(v, spec[len("list_of_"):]) for v in value]
        except ValueError as exc:
            raise param.error(f"value {value!r} is not {type_name(spec)} ({exc})",
                              at="value") from None
        return value


def _form_type(default: Any) -> str:
    """The editor the argument form offers: a checkbox for a true/false default, ..."""
    if not isinstance(default, str):
        return "str"
    if default.lower() in ("true", "false"):
        return "bool"
    for kind, convert in (("int", int), ("float", float)):
        try:
            convert(default)
        except ValueError:
            continue
        return kind
    return "str"


def _yaml_typed(value: Any) -> Any:
    """`set_parameter` values are read with YAML rules, as launch_ros does."""
    return TextSubstitution(value) if isinstance(value, str) else value

