"""ROS messages as plain dicts and back, with errors that name the field at fault.

Used for `call_service` requests from launch files, and for the service panel's forms.
"""

from __future__ import annotations

import importlib
import re
from dataclasses import dataclass, field
from typing import Any

from .ros_errors import MessageError

_SEQUENCE = re.compile(r"^sequence<([^,>]+)(?:,\s*\d+)?>$")
_ARRAY = re.compile(r"^(.+)\[(\d*)\]$")
_BOUNDED_STRING = re.compile(r"^(w?string)<=\d+$")


def import_type(type_name: str, kind: str = "srv") -> Any:
    """`std_srvs/srv/Trigger` (or `std_srvs/Trigger`) to its Python class."""
    parts = type_name.split("/")
    if len(parts) == 2:
        parts = [parts[0], kind, parts[1]]
    if len(parts) != 3:
        raise MessageError(f"'{type_name}' is not a ROS type name (package/{kind}/Name)")
    try:
        module = importlib.import_module(f"{parts[0]}.{parts[1]}")
        return getattr(module, parts[2])
    except (ImportError, AttributeError):
        raise MessageError(f"type '{type_name}' is not installed in this environment",
                           hint=f"install the package that defines it ({parts[0]})") from None


def element_type(type_text: str) -> tuple[str, bool]:
    """The element type of a field, and whether the field is a sequence or array."""
    for pattern in (_SEQUENCE, _ARRAY):
        match = pattern.match(type_text)
        if match:
            return match.group(1), True
    return type_text, False


_INT_RANGES = {
    "int8": (-(2**7), 2**7 - 1), "uint8": (0, 2**8 - 1), "byte": (0, 255), "octet": (0, 255),
    "char": (0, 255), "int16": (-(2**15), 2**15 - 1), "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1), "uint64": (0, 2**64 - 1),
}
_FLOATS = ("float", "double", "float32", "float64")


def check_basic(base: str, value: Any, where: str) -> Any:
    """A scalar checked (and ints widened to float) against a basic ROS type.

    Generated message setters skip their own checks unless ROS_PYTHON_CHECK_FIELDS is set,
    so a wrong value would otherwise reach the wire silently.
    """
    base = _BOUNDED_STRING.sub(r"\1", base)
    ok = True
    if base == "boolean":
        ok = isinstance(value, bool)
    elif base in _INT_RANGES:
        low, high = _INT_RANGES[base]
        ok = isinstance(value, int) and not isinstance(value, bool) and low <= value <= high
    elif base in _FLOATS:
        ok = isinstance(value, int | float) and not isinstance(value, bool)
        value = float(value) if ok else value
    elif base in ("string", "wstring"):
        ok = isinstance(value, str)
    if not ok:
        raise MessageError(f"field '{where}' needs a {base}, got {value!r}")
    return value


def is_message_type(type_text: str) -> bool:
    base = _BOUNDED_STRING.sub(r"\1", type_text)
    return "/" in base


def _message_class(type_text: str) -> Any:
    return import_type(type_text, "msg")


@dataclass
class FieldInfo:
    """One field of a message, for building a form."""

    name: str
    type: str
    default: Any
    is_sequence: bool
    children: list[FieldInfo] = field(default_factory=list)


def describe_fields(message_class: Any) -> list[FieldInfo]:
    instance = message_class()
    out = []
    for name, type_text in message_class.get_fields_and_field_types().items():
        base, sequence = element_type(type_text)
        children = []
        if is_message_type(base) and not sequence:
            children = describe_fields(_message_class(base))
        default = to_plain(getattr(instance, name))
        out.append(FieldInfo(name, type_text, default, sequence, children))
    return out


def fill(message: Any, values: dict[str, Any], path: str = "") -> Any:
    """Set a message's fields from a dict; missing fields keep their defaults."""
    types = message.get_fields_and_field_types()
    for name, value in values.items():
        where = f"{path}{name}"
        if name not in types:
            raise MessageError(
                f"field '{where}' does not exist in {type(message).__name__}",
                hint=f"fields: {', '.join(types) or '(none)'}")
        type_text = types[name]
        base, sequence = element_type(type_text)
        if is_message_type(base):
            if sequence:
                if not isinstance(value, list):
                    raise MessageError(f"field '{where}' ({type_text}) needs a list, got "
                                       f"{value!r}")
                cls = _message_class(base)
                value = [fill(cls(), item, f"{where}[{i}].") if isinstance(item, dict)
                         else item for i, item in enumerate(value)]
            elif isinstance(value, dict):
                fill(getattr(message, name), value, f"{where}.")
                continue
        elif sequence:
            if not isinstance(value, list | tuple):
                raise MessageError(f"field '{where}' ({type_text}) needs a list, got {value!r}")
            value = [check_basic(base, v, f"{where}[{i}]") for i, v in enumerate(value)]
        else:
            value = check_basic(base, value, where)
        try:
            setattr(message, name, value)
        except (AssertionError, TypeError, ValueError) as exc:
            detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise MessageError(f"field '{where}' ({type_text}) cannot take {value!r}: {detail}")\
                from None
    return message


def to_plain(value: Any) -> Any:
    """A message (or field value) as dicts, lists and scalars, for YAML and JSON."""
    if hasattr(value, "get_fields_and_field_types"):
        return {name: to_plain(getattr(value, name))
                for name in value.get_fields_and_field_types()}
    if isinstance(value, list | tuple):
        return [to_plain(v) for v in value]
    if hasattr(value, "tolist"):  # numpy arrays and array.array
        return value.tolist()
    if isinstance(value, bytes):
        return list(value)
    return value
