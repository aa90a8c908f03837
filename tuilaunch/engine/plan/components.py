"""Composable nodes as a plan holds them: the LoadNode request each one will send.

Follows launch_ros's `get_composable_node_load_request`: the namespace is the launch's
pushed namespace joined with the component's own (not the container's); remappings are the
scope's `SetRemap`s then the component's; parameters are the scope's `SetParameter`s, then
each dict or file in order, a file giving its `/**` entry then the entry of the component's
`namespace/name`; `extra_arguments` are parameters for the container itself.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
from collections.abc import Callable
from typing import Any

from ..describe.entities import ComposableNode, pair_list
from ..describe.parameter_files import dotted, node_sections
from ..describe.substitutions import PerformContext, perform, perform_optional
from ..describe.values import ParamValue, flatten_parameters
from ..errors import LaunchError, Origin
from .scope import join_namespace


def _items(value: Any) -> list[Any]:
    if value is None:
        return []
    return list(value) if isinstance(value, list | tuple) else [value]


def file_parameters(path: str, node_key: str, origin: Origin | None,
                    substitute: Callable[[str], str] | None = None) -> dict[str, Any]:
    """The parameters a file gives a component named `node_key` (`ns/name`, no leading /).

    `substitute` performs `$(var x)` and friends in the text first (ParameterFile with
    allow_substs)."""
    import yaml  # here: a launch without components does not load it

    try:
        with open(path) as handle:
            text = handle.read()
        loaded = yaml.safe_load(substitute(text) if substitute else text) or {}
    except OSError as exc:
        raise LaunchError(f"parameter file {path} cannot be read: {exc.strerror}",
                          origin) from None
    except yaml.YAMLError as exc:
        raise LaunchError(f"parameter file {path} is not valid YAML: {exc}", origin) from None
    if not isinstance(loaded, dict):
        raise LaunchError(f"parameter file {path} does not hold a mapping", origin)
    sections = node_sections(loaded)
    if not sections:
        return dotted(loaded)
    values: dict[str, Any] = {}
    for key in ("**", node_key):
        if key in sections:
            values.update(dotted(sections[key]))
    return values


def _file_path(item: Any, ctx: PerformContext) -> str:
    """A parameter file given as a path, a substitution, or a ParameterFile."""
    source = getattr(item, "param_file", item)
    return perform(source, ctx)


def _substituter(item: Any, ctx: PerformContext, origin: Origin | None)\
        -> Callable[[str], str] | None:
    """For a ParameterFile(allow_substs=True): performs the substitutions in its text."""
    substitutes = getattr(item, "substitutes", None)
    if not callable(substitutes) or not substitutes(ctx):
        return None
    try:  # the launch_ros ParameterFile's own text substitution
        module = importlib.import_module("tuilaunch.engine.describe.parameter_files")
        substitute_text = module.substitute_text
    except (ImportError, AttributeError):
        return None
    return lambda text: str(substitute_text(text, ctx, origin))


def component_plan(component: ComposableNode, ctx: PerformContext, scope_namespace: str,
                   global_parameters: list[tuple[Any, Any]], remaps: list[tuple[Any, Any]],
                   component_id: str, container: str | None) -> dict[str, Any]:
    """One component's load request and what the plan shows about it.

    `global_parameters` are the scope's SetParameter pairs and SetParametersFromFile files
    (key None), in order, applied before the component's own parameters."""
    origin = component.origin
    condition = getattr(component, "condition", None)
    outcome = True if condition is None else condition.evaluate(ctx)
    enabled = bool(getattr(outcome, "holds", outcome))
    name = perform_optional(component.name, ctx) or ""
    own_ns = perform_optional(component.namespace, ctx)
    pushed = None if scope_namespace == "/" else scope_namespace
    request_ns = "" if pushed is None and not own_ns else join_namespace(pushed or "/", own_ns)
    node_key = name.lstrip("/")
    if request_ns and request_ns != "/":
        node_key = f"{request_ns.strip('/')}/{node_key}"
    params: dict[str, ParamValue] = {}
    files: list[str] = []
    error = None
    global_items = [value if key is None else {key: value} for key, value in global_parameters]
    for item in [*global_items, *_items(component.parameters)]:
        if isinstance(item, dict):
            params.update(flatten_parameters(item, ctx, origin))
            continue
        path = _file_path(item, ctx)
        files.append(path)
        if not os.path.isfile(path):
            error = f"parameter file {path} does not exist"
            continue
        params.update(file_parameters(path, node_key, origin, _substituter(item, ctx, origin)))
    remappings = [[perform(a, ctx), perform(b, ctx)]
                  for a, b in [*remaps, *pair_list(component.remappings, "remappings", origin)]]
    extra: dict[str, ParamValue] = {}
    for item in _items(component.extra_arguments):
        if isinstance(item, dict):
            extra.update(flatten_parameters(item, ctx, origin))
    package = perform(component.package, ctx)
    plugin = perform(component.plugin, ctx)
    shown_ns = request_ns or "/"
    full_name = (join_namespace(shown_ns, name) if name else None)
    return {
        "id": component_id,
        "package": package,
        "plugin": plugin,
        "name": name or None,
        "namespace": shown_ns,
        "full_name": full_name,
        "request": {"package_name": package, "plugin_name": plugin, "node_name": name,
                    "node_namespace": request_ns,
                    "remap_rules": [f"{a}:={b}" for a, b in remappings]},
        "parameters": params,
        "parameter_files": files,
        "remappings": remappings,
        "extra_arguments": extra,
        "container": container,
        "enabled": enabled,
        "origin": str(origin) if origin else None,
        "error": error,
    }


def interfaces_warning(component_count: int) -> list[str]:
    """Said at plan time too: without composition_interfaces no component can load."""
    if component_count and importlib.util.find_spec("composition_interfaces") is None:
        return [f"composition_interfaces is not installed: the {component_count} "
                "component(s) of this launch will not load (source /opt/ros/jazzy)"]
    return []


def component_label(component: dict[str, Any]) -> str:
    """`/ns/name (pkg::Plugin)`, or `<pkg::Plugin>` when the plugin names itself."""
    namespace = component["namespace"].rstrip("/")
    who = component.get("full_name") or f"{namespace}/<{component['plugin']}>"
    return f"{who} ({component['plugin']})"


__all__ = ["component_label", "component_plan", "file_parameters"]
