"""A message type's full definition, as rosbag2's MCAP storage writes a channel's schema
(encoding `ros2msg`): the type's .msg text, then each type it depends on (once, depth first)
after a line of 80 `=` and a line `MSG: pkg/Type`.

The texts come from the installed interface packages' `share/<pkg>/msg/<Type>.msg`, found
through the ament prefixes (engine/packages.py): a virtualenv of ROS wheels and a sourced
/opt/ros alike. A type whose .msg is not installed gets an empty definition (rosbag2 does
the same): its messages are still recorded, a reader without the type cannot decode them.
"""

from __future__ import annotations

import re
from functools import lru_cache

from ...errors import PackageError
from ...packages import package_share

DELIMITER = "=" * 80
PRIMITIVES = frozenset({
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
    "int32", "uint32", "int64", "uint64", "string", "wstring", "duration", "time"})
_FIELD = re.compile(r"^\s*([A-Za-z_][\w/]*)")


def short_name(type_name: str) -> str:
    """`std_msgs/msg/String` -> `std_msgs/String` (the `MSG:` lines' form)."""
    parts = type_name.split("/")
    return f"{parts[0]}/{parts[-1]}" if len(parts) == 3 else type_name


@lru_cache(maxsize=512)
def msg_text(type_name: str) -> str | None:
    """The installed .msg text of `pkg/msg/Type` (or `pkg/Type`), None when not installed."""
    parts = type_name.split("/")
    if len(parts) not in (2, 3):
        return None
    try:
        path = package_share(parts[0]) / "msg" / f"{parts[-1]}.msg"
        return path.read_text()
    except (PackageError, OSError):
        return None


def dependencies(text: str, package: str) -> list[str]:
    """The non-primitive field types of a .msg text, as `pkg/Type`, in order of use: an
    unqualified type is of the same package (`Header` is std_msgs')."""
    found: list[str] = []
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        match = _FIELD.match(line)
        if match is None or len(line.split()) < 2:  # a field or a constant: type, name
            continue
        base = re.sub(r"<=?\d+$", "", match.group(1))
        if base in PRIMITIVES or base.startswith(("string<", "wstring<")):
            continue
        if "/" in base:
            named = short_name(base)
        elif base == "Header":
            named = "std_msgs/Header"
        else:
            named = f"{package}/{base}"
        if named not in found:
            found.append(named)
    return found


@lru_cache(maxsize=512)
def full_definition(type_name: str) -> str:
    """The `ros2msg` schema text of `pkg/msg/Type`; "" when its .msg is not installed."""
    root = msg_text(type_name)
    if root is None:
        return ""
    parts = [root.rstrip("\n")]
    seen = {short_name(type_name)}
    pending = dependencies(root, type_name.split("/")[0])
    while pending:
        dep = pending.pop(0)
        if dep in seen:
            continue
        seen.add(dep)
        text = msg_text(dep)
        if text is None:
            continue
        parts.append(f"{DELIMITER}\nMSG: {dep}\n{text.rstrip(chr(10))}")
        # depth first: this type's own dependencies come before its siblings'
        pending[:0] = [d for d in dependencies(text, dep.split("/")[0]) if d not in seen]
    return "\n".join(parts) + "\n"


__all__ = ["full_definition", "short_name"]
