"""`launch.utilities`, `launch.utilities.type_utils` and `launch_ros.utilities` for extensions.

Third-party Substitutions and Actions (nav2_common's RewrittenYaml, ros2_control helpers)
normalise their arguments and perform them with these functions.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from typing import Any

from ...errors import DslError, caller_origin
from ..substitutions import PerformContext, Substitution, TextSubstitution, flatten, perform


def normalize_to_list_of_substitutions(subs: Any) -> list[Substitution]:
    """Text, a substitution or a list of them, as a list of substitutions."""
    out: list[Substitution] = []
    for part in flatten(subs):
        out.append(part if isinstance(part, Substitution) else TextSubstitution(str(part)))
    return out


def perform_substitutions(context: PerformContext, subs: Any) -> str:
    return perform(subs, context)


def normalize_to_list_of_entities(entities: Iterable[Any]) -> list[Any]:
    from ..entities import entity_list

    return entity_list(list(entities))


def is_a(obj: Any, entity_type: Any) -> bool:
    return isinstance(obj, entity_type)


def is_a_subclass(obj: Any, entity_type: Any) -> bool:
    return isinstance(obj, type) and issubclass(obj, entity_type)


def isclassinstance(obj: Any) -> bool:
    return hasattr(obj, "__class__")


def ensure_argument_type(argument: Any, types: Any, argument_name: str,
                         caller: str | None = None) -> None:
    kinds = tuple(types) if isinstance(types, list | tuple) else (types,)
    if not isinstance(argument, kinds):
        where = f"{caller}: " if caller else ""
        raise DslError(f"{where}argument '{argument_name}' should be one of "
                       f"{', '.join(getattr(t, '__name__', str(t)) for t in kinds)}, got "
                       f"{type(argument).__name__}", caller_origin())


# --- launch.utilities.type_utils -----------------------------------------------------


def is_substitution(value: Any) -> bool:
    return isinstance(value, Substitution) or (
        isinstance(value, list | tuple) and any(isinstance(v, Substitution) for v in value))


def normalize_typed_substitution(value: Any, data_type: Any = None) -> Any:
    return normalize_to_list_of_substitutions(value) if is_substitution(value) else value


def coerce_to_type(value: str, data_type: Any = None, *, can_be_str: bool = False) -> Any:
    if data_type is str:
        return value
    if data_type in (int, float):
        return data_type(value)
    if data_type is bool:
        return value.strip().lower() in ("true", "1")
    import yaml  # here: a launch that never reads a value as YAML does not load it

    try:
        return yaml.safe_load(value)
    except yaml.YAMLError:
        return value


def perform_typed_substitution(context: PerformContext, value: Any, data_type: Any = None)\
        -> Any:
    if is_substitution(value):
        return coerce_to_type(perform(value, context), data_type)
    return value


def get_typed_value(value: str, data_type: Any = None, *, can_be_str: bool = True) -> Any:
    return coerce_to_type(value, data_type, can_be_str=can_be_str)


# --- launch_ros.utilities ------------------------------------------------------------


def is_root_namespace(namespace: str) -> bool:
    return namespace == "/"


def is_namespace_absolute(namespace: str) -> bool:
    return namespace.startswith("/")


def make_namespace_absolute(namespace: str | None) -> str | None:
    if namespace is None or namespace.startswith("/"):
        return namespace
    return "/" + namespace


def prefix_namespace(base_ns: str | None, namespace: str | None) -> str | None:
    """launch_ros's namespace joining: relative after the base, absolute as is."""
    if base_ns is None:
        return namespace
    if namespace is None:
        return base_ns
    if namespace.startswith("/"):
        return namespace
    return os.path.join(base_ns, namespace) if base_ns != "/" else "/" + namespace


def normalize_remap_rules(remappings: Any) -> list[tuple[list[Substitution], list[Substitution]]]:
    from ..entities import pair_list

    return [(normalize_to_list_of_substitutions(a), normalize_to_list_of_substitutions(b))
            for a, b in pair_list(remappings, "remappings")]


_node_names: dict[str, int] = {}


def add_node_name(context: Any, node_name: str) -> None:
    _node_names[node_name] = _node_names.get(node_name, 0) + 1


def get_node_name_count(context: Any, node_name: str) -> int:
    return _node_names.get(node_name, 0)
