"""A message's numeric fields by dotted path, as a plot names them: `data`,
`pose.pose.position.x`, `ranges[0]`, `points[2].y`.

The paths are read from the message class's own description (its SLOT_TYPES, rosidl's
parsed .msg), not from a sample: a field is checked before the first message comes, and
an error lists every numeric field the topic has. Fixed-size arrays list each element
(up to LISTED_ELEMENTS); a sequence, whose length only a message knows, lists each element
of a sample message when one is given (`position[0..n]` of the joint states received last),
else its first; any index is accepted (a message too short for it has no value there).
"""

from __future__ import annotations

import importlib
import re
from dataclasses import dataclass
from typing import Any

NUMERIC = frozenset({"float", "double", "long double", "int8", "uint8", "int16", "uint16",
                     "int32", "uint32", "int64", "uint64", "boolean"})
"""rosidl's basic types a plot can draw (a boolean as 0 and 1); `char`, `octet` are bytes."""
INTEGERS = NUMERIC - {"float", "double", "long double"}
"""Printed without a decimal point by `tuilaunch plot --csv` (a boolean as 0 or 1)."""
LISTED_ELEMENTS = 64
"""Elements of a fixed-size array listed one by one (a covariance's 36 are)."""
SHOWN_IN_ERROR = 24
"""Numeric fields named in an error before `... (N more)`."""

_STEP = re.compile(r"^([A-Za-z_]\w*)((?:\[\d+\])*)$")


class FieldError(ValueError):
    """A path that names no numeric field of the type; the text says which ones exist."""


@dataclass(frozen=True)
class FieldPath:
    """A compiled path: the steps to walk (an attribute, then indexes into it) and the
    basic type at its end (`float` values are 32-bit: printed as such)."""

    path: str
    steps: tuple[tuple[str, tuple[int, ...]], ...]
    basic: str

    def value(self, message: Any) -> float | None:
        """The field's value in `message` as a float; None where a sequence is too short."""
        value = message
        try:
            for name, indexes in self.steps:
                value = getattr(value, name)
                for index in indexes:
                    value = value[index]
        except IndexError:
            return None
        return float(value)


def _slots(cls: Any) -> list[tuple[str, Any]]:
    """(field name, rosidl type) of a message class, in the .msg's order."""
    names = list(cls.get_fields_and_field_types())
    return list(zip(names, cls.SLOT_TYPES, strict=True))


def _nested_class(kind: Any) -> Any:
    """The Python class of a NamespacedType (`geometry_msgs/msg/Pose`)."""
    module = importlib.import_module(".".join(kind.namespaces))
    return getattr(module, kind.name)


def _basic(kind: Any) -> str | None:
    """A BasicType's name, or None for anything else."""
    name = getattr(kind, "typename", None)
    return name if isinstance(name, str) and not hasattr(kind, "value_type") else None


def numeric_fields(cls: Any, prefix: str = "", depth: int = 0,
                   sample: Any = None) -> list[str]:
    """Every numeric field of a message class by dotted path, in the .msg's order;
    `sample`: a message of it, whose sequences' lengths are listed (each element, up to
    LISTED_ELEMENTS) where the type alone offers a sequence's first element."""
    found: list[str] = []
    if depth > 16:  # message types do not nest this deep; a guard, not a limit met
        return found
    for name, kind in _slots(cls):
        path = f"{prefix}{name}"
        value = getattr(sample, name, None) if sample is not None else None
        value_type = getattr(kind, "value_type", None)
        if value_type is None:
            found += _leaf_fields(kind, path, depth, value)
            continue
        size = getattr(kind, "size", None)  # an Array; a sequence has maximum_size or none
        if not isinstance(size, int):
            size = len(value) if value is not None and len(value) > 0 else 1
        for index in range(min(size, LISTED_ELEMENTS)):
            element = value[index] if value is not None and index < len(value) else None
            found += _leaf_fields(value_type, f"{path}[{index}]", depth, element)
    return found


def _leaf_fields(kind: Any, path: str, depth: int, sample: Any = None) -> list[str]:
    basic = _basic(kind)
    if basic is not None:
        return [path] if basic in NUMERIC else []
    if hasattr(kind, "namespaces"):
        return numeric_fields(_nested_class(kind), path + ".", depth + 1, sample)
    return []  # strings


def has_sequences(cls: Any, depth: int = 0) -> bool:
    """Whether a message of the type may hold a sequence (whose length only a message
    knows): the field picker then asks for one message to list every element."""
    if depth > 16:
        return False
    for _, kind in _slots(cls):
        element = getattr(kind, "value_type", None)
        if element is not None:
            if not isinstance(getattr(kind, "size", None), int):
                return True
            kind = element
        if hasattr(kind, "namespaces") and has_sequences(_nested_class(kind), depth + 1):
            return True
    return False


STAMP = "header.stamp"
"""Where a message's own time is (std_msgs/Header): `--stamp` plots against it."""


def stamp_reader(cls: Any) -> Any:
    """A function reading a message's header.stamp in seconds (epoch, or the sim clock's),
    or None when the type has no header.stamp."""
    try:
        compile_path(cls, f"{STAMP}.sec")
        compile_path(cls, f"{STAMP}.nanosec")
    except FieldError:
        return None

    def stamp(message: Any) -> float:
        time = message.header.stamp
        return float(time.sec) + time.nanosec * 1e-9

    return stamp


def small(cls: Any, depth: int = 0) -> bool:
    """Whether every message of the type is small: no sequence without a bound (a point
    cloud's data, a scan's ranges), strings aside (a frame id is short). A sampler may
    keep many of them waiting (streams.py)."""
    if depth > 16:
        return False
    for _, kind in _slots(cls):
        element = getattr(kind, "value_type", None)
        if element is not None:
            if not isinstance(getattr(kind, "size", None), int) and \
                    not isinstance(getattr(kind, "maximum_size", None), int):
                return False
            kind = element
        if hasattr(kind, "namespaces") and not small(_nested_class(kind), depth + 1):
            return False
    return True


def compile_path(cls: Any, path: str, topic: str = "") -> FieldPath:
    """`path` checked against the type: a FieldError naming the topic and its numeric
    fields unless it leads to a numeric value."""
    steps: list[tuple[str, tuple[int, ...]]] = []
    current = cls
    basic: str | None = None
    parts = path.split(".") if path else [""]
    for position, part in enumerate(parts):
        match = _STEP.match(part)
        if match is None or current is None:
            raise _not_numeric(cls, path, topic)
        name, index_text = match.group(1), match.group(2)
        indexes = tuple(int(i) for i in re.findall(r"\d+", index_text))
        kinds = dict(_slots(current))
        if name not in kinds:
            raise _not_numeric(cls, path, topic)
        kind = kinds[name]
        if indexes:
            if len(indexes) != 1 or getattr(kind, "value_type", None) is None:
                raise _not_numeric(cls, path, topic)  # ROS has no arrays of arrays
            size = getattr(kind, "size", None)
            limit = getattr(kind, "maximum_size", None) if size is None else size
            if isinstance(limit, int) and indexes[0] >= limit:
                raise _not_numeric(cls, path, topic)
            kind = kind.value_type
        elif getattr(kind, "value_type", None) is not None:
            raise _not_numeric(cls, path, topic)  # a whole array is no one number
        steps.append((name, indexes))
        last = position == len(parts) - 1
        basic = _basic(kind)
        if last:
            if basic not in NUMERIC:
                raise _not_numeric(cls, path, topic)
        elif hasattr(kind, "namespaces"):
            current = _nested_class(kind)
        else:
            current = None  # a step past a number or a string
    assert basic is not None
    return FieldPath(path, tuple(steps), basic)


def type_name(cls: Any) -> str:
    """`std_msgs/msg/Float64` for a message class."""
    module = cls.__module__.split(".")
    return f"{module[0]}/msg/{cls.__name__}"


def fields_text(cls: Any) -> str:
    """The numeric fields for an error: all, or the first SHOWN_IN_ERROR and a count."""
    fields = numeric_fields(cls)
    if not fields:
        return "it has no numeric field"
    shown = ", ".join(fields[:SHOWN_IN_ERROR])
    more = len(fields) - SHOWN_IN_ERROR
    return f"its numeric fields: {shown}" + (f", ... ({more} more)" if more > 0 else "")


def _not_numeric(cls: Any, path: str, topic: str) -> FieldError:
    where = f"{topic} ({type_name(cls)})" if topic else type_name(cls)
    return FieldError(f"{where} has no numeric field {path!r}; {fields_text(cls)}")
