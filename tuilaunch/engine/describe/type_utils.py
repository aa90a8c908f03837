"""Typed attribute values, following launch's frontend rules.

A type is named as launch's `type=` attribute names it: `str`, `int`, `float`, `bool`,
`list_of_str`, `list_of_int`, `list_of_float`, `list_of_bool`, or `yaml` (launch's
`data_type=None`: read the text with YAML rules and keep a scalar or a uniform list).
XML attributes are text and are coerced; YAML values are checked (scalars given where text
is expected are taken as their text, as a user would expect).
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from ..errors import LaunchError, Origin
from .substitutions import PerformContext, perform

TypeSpec = str

SCALARS = {"str": str, "int": int, "float": float, "bool": bool}
TYPE_IDENTIFIERS = (*SCALARS, *(f"list_of_{name}" for name in SCALARS), "yaml")


def type_name(spec: TypeSpec) -> str:
    if spec == "yaml":
        return "a YAML value (a number, true/false, text or a list of one of those)"
    if spec.startswith("list_of_"):
        return f"a list of {spec[len('list_of_'):]}"
    return {"int": "an integer", "float": "a number", "bool": "true or false",
            "str": "text"}.get(spec, spec)


def check_identifier(identifier: str) -> TypeSpec:
    if identifier not in TYPE_IDENTIFIERS:
        raise ValueError(f"type '{identifier}' is not one of {', '.join(TYPE_IDENTIFIERS)}")
    return identifier


def _valid_value(value: Any, can_be_str: bool) -> bool:
    """A scalar, or a list whose items share one scalar type (text mixed in if can_be_str)."""
    if isinstance(value, list):
        kinds = {type(item) for item in value}
        if not kinds <= {bool, int, float, str}:
            return False
        if can_be_str:
            kinds.discard(str)
        return len(kinds) <= 1
    return isinstance(value, bool | int | float | str)


def _numbers_as_floats(value: Any) -> Any:
    """[1, 2.5] is a list of floats to a user (launch itself would refuse the mix)."""
    if isinstance(value, list) and value and {type(v) for v in value} == {int, float}:
        return [float(v) for v in value]
    return value


@lru_cache(maxsize=4096)
def _yaml_load_cached(text: str) -> Any:
    # pyyaml imported on first use: a launch of plain processes starts without it; libyaml
    # when present: files repeat the same short values thousands of times
    import yaml

    return yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))


def _yaml_load(text: str) -> Any:
    value = _yaml_load_cached(text)
    return list(value) if isinstance(value, list) else value  # the cache keeps its own copy


def _as_yaml(text: str, can_be_str: bool) -> Any:
    if not text:
        return text
    import yaml

    try:
        value = _numbers_as_floats(_yaml_load(text))
    except yaml.YAMLError:
        if can_be_str:
            return text
        raise ValueError("not valid YAML") from None
    if not _valid_value(value, can_be_str):
        if can_be_str and (value is None or isinstance(value, dict)):
            return text
        raise ValueError(f"YAML reads it as {type(value).__name__}, which a launch value "
                         "cannot be")
    return value


def coerce_text(text: str, spec: TypeSpec, can_be_str: bool = False) -> Any:
    """Text from an XML attribute (or a performed substitution) as the given type."""
    if spec == "yaml":
        return _as_yaml(text, can_be_str)
    if spec.startswith("list_of_"):
        item = SCALARS[spec[len("list_of_"):]]
        value = _as_yaml(text, can_be_str)
        allowed: tuple[type, ...] = (item, str) if can_be_str else (item,)
        if item is float:
            allowed = (*allowed, int)
        if not isinstance(value, list) or not all(
                isinstance(v, allowed) and (item is bool or not isinstance(v, bool))
                for v in value):
            raise ValueError(f"expected a list of {item.__name__} like [1, 2]")
        return [float(v) if item is float and not isinstance(v, str) else v for v in value]
    kind = SCALARS[spec]
    if kind is str:
        return text
    if kind is int or kind is float:
        try:
            return kind(text)
        except ValueError:
            if can_be_str:
                return text
            raise ValueError(f"expected {type_name(spec)}") from None
    lowered = {"1": "true", "0": "false"}.get(text, text)
    value = _as_yaml(lowered, can_be_str)
    if isinstance(value, bool):
        return value
    if can_be_str and isinstance(value, str):
        return text
    raise ValueError("expected true or false")


def check_yaml_value(value: Any, spec: TypeSpec, can_be_str: bool = True) -> Any:
    """A value from a YAML launch file, checked against the type asked for."""
    if isinstance(value, str):
        if spec in ("str", "yaml") or can_be_str:
            return value  # YAML quoted it: it is text (maybe with substitutions)
        return coerce_text(value, spec, can_be_str)
    if spec == "str":
        if isinstance(value, bool):
            return str(value).lower()
        if isinstance(value, int | float | str):
            return str(value)
        raise ValueError(f"expected text, got {type(value).__name__}")
    if spec == "yaml":
        value = _numbers_as_floats(value)
        if not _valid_value(value, can_be_str):
            raise ValueError(f"{type(value).__name__} is not a launch value")
        return value
    if spec.startswith("list_of_"):
        if not isinstance(value, list):
            raise ValueError("expected a list")
        import yaml

        return coerce_text(yaml.safe_dump(value, default_flow_style=True), spec, can_be_str)
    kind = SCALARS[spec]
    if kind is bool:
        if isinstance(value, bool):
            return value
        if value in (0, 1):
            return bool(value)
        raise ValueError("expected true or false")
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"expected {type_name(spec)}")
    if kind is int and isinstance(value, float) and not value.is_integer():
        raise ValueError("expected an integer")
    return kind(value)


def typed_parameter(value: Any, spec: TypeSpec, context: PerformContext, where: str,
                    origin: Origin | None) -> Any:
    """A parameter whose file gave `type=`, coerced once its substitutions are performed."""
    if spec == "str":
        return perform(value, context)
    if isinstance(value, list):
        item_spec = spec[len("list_of_"):] if spec.startswith("list_of_") else "yaml"
        items = [typed_parameter(v, item_spec, context, where, origin) for v in value]
        return items
    text = perform(value, context)
    try:
        return coerce_text(text, spec, can_be_str=False)
    except ValueError as exc:
        raise LaunchError(f"parameter '{where}' = {text!r} is not {type_name(spec)}: {exc}",
                          origin, hint="check the value, or the param's type=") from None
