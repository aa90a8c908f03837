"""Node parameters as typed values.

Values known only as substitutions are read as YAML once performed, as launch_ros does, so
`x:=1` reaches a node as an integer; xacro output always stays a string.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from ..errors import LaunchError, Origin
from .substitutions import PerformContext, Substitution, flatten, perform
from .type_utils import typed_parameter

ParamValue = bool | int | float | str | list[Any]


class ParameterValue:
    """launch_ros.parameter_descriptions.ParameterValue: a value with an explicit type."""

    def __init__(self, value: Any, *, value_type: Any = None) -> None:
        self.value = value
        self.value_type = value_type


def _is_string_typed(value: Any) -> bool:
    parts = flatten(value)
    return any(getattr(p, "string_typed", False) for p in parts) or any(
        getattr(sub, "string_typed", False)
        for p in parts if hasattr(p, "parts") for sub in flatten(p.parts)
    )


def yaml_typed(text: str) -> ParamValue:
    """A performed string as ROS would type it: bool, int, float, homogeneous list or str."""
    typed = _yaml_typed(text)
    return list(typed) if isinstance(typed, tuple) else typed  # each caller its own list


@lru_cache(maxsize=1024)
def _yaml_typed(text: str) -> bool | int | float | str | tuple[Any, ...]:
    # cached: the same argument reaches every node of a large plan, and pyyaml's parser costs
    # a tenth of a millisecond a value
    import yaml  # here, not at the top: a launch without parameters starts sooner

    try:
        loaded = yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError:
        return text
    if isinstance(loaded, bool | int | float | str):
        return loaded
    if isinstance(loaded, list) and loaded and all(isinstance(v, bool | int | float | str)
                                                   for v in loaded):
        return tuple(loaded)
    return text


def yaml_single_quoted(text: str) -> str:
    """simple_launch's xacro output, which it wraps in single quotes for launch_ros to read
    as YAML: always a string, with line breaks folded to spaces as YAML folds them."""
    import yaml

    try:
        loaded = yaml.safe_load("'" + text + "'")
    except yaml.YAMLError:
        return text
    return loaded if isinstance(loaded, str) else text


def typed_value(value: Any, context: PerformContext, where: str, origin: Origin | None)\
        -> ParamValue:
    if isinstance(value, ParameterValue):
        if value.value_type is str:
            return perform(value.value, context)
        if isinstance(value.value_type, str):  # a frontend's type=: int, list_of_float, ...
            return typed_parameter(value.value, value.value_type, context, where, origin)
        return typed_value(value.value, context, where, origin)
    if isinstance(value, bool | int | float):
        return value
    if isinstance(value, str):
        return value
    if isinstance(value, Substitution):
        text = perform(value, context)
        return yaml_single_quoted(text) if _is_string_typed(value) else yaml_typed(text)
    if isinstance(value, list | tuple):
        if any(isinstance(v, Substitution) for v in value) and all(
                isinstance(v, str | Substitution) for v in value) and not all(
                isinstance(v, Substitution) for v in value):
            # launch's convention: a list mixing text and substitutions is one concatenation
            return yaml_typed(perform(list(value), context))
        items = [typed_value(v, context, where, origin) for v in value]
        kinds = {type(v) for v in items}
        if kinds <= {int, float} and float in kinds:
            items = [float(v) for v in items if isinstance(v, int | float)]
        elif len(kinds) > 1:
            raise LaunchError(
                f"parameter '{where}' mixes types in a list: {items!r}", origin,
                hint="ROS parameter arrays hold one type")
        return items
    raise LaunchError(f"parameter '{where}' has a value of unsupported type "
                      f"{type(value).__name__}: {value!r}", origin)


def flatten_parameters(params: dict[Any, Any], context: PerformContext, origin: Origin | None,
                       prefix: str = "") -> dict[str, ParamValue]:
    """Nested dicts become dotted names (`{'a': {'b': 1}}` -> `a.b`)."""
    out: dict[str, ParamValue] = {}
    for key, value in params.items():
        name = prefix + perform(key, context)
        if isinstance(value, dict):
            out.update(flatten_parameters(value, context, origin, name + "."))
        else:
            out[name] = typed_value(value, context, name, origin)
    return out
