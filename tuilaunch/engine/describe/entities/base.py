"""The base of every entity, the LaunchDescription that lists them, a launch argument,
and the helpers that read a launch API's loose arguments (an entity, a list; a dict or
pairs)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from ...errors import DslError, Origin, caller_origin
from ..conditions import Condition
from ..substitutions import SubValue


class Entity:
    """Anything that can stand in a launch description."""

    condition: Condition | None = None
    origin: Origin | None = None

    def __init__(self, *, condition: Condition | None = None, **_: Any) -> None:
        """launch.Action's constructor, for third-party actions (`execute(context)`)."""
        self._init_entity(condition)

    def _init_entity(self, condition: Condition | None) -> None:
        self.condition = condition
        self.origin = caller_origin()

    def describe(self) -> str:
        return type(self).__name__


Action = Entity


def entity_list(value: Any, what: str = "actions") -> list[Any]:
    """Entities from a single one, a list, or a LaunchDescription; callables kept as-is."""
    if value is None:
        return []
    if isinstance(value, LaunchDescription):
        return list(value.entities)
    if isinstance(value, list | tuple):
        out: list[Any] = []
        for item in value:
            out.extend(entity_list(item, what))
        return out
    if isinstance(value, Entity) or callable(value):
        return [value]
    raise DslError(
        f"{what} must be launch actions, got {type(value).__name__} {value!r}", caller_origin()
    )


class LaunchDescription(Entity):
    def __init__(self, initial_entities: Iterable[Any] | None = None) -> None:
        self._init_entity(None)
        self.entities: list[Any] = entity_list(list(initial_entities or []))

    def add_action(self, action: Any) -> None:
        self.entities.extend(entity_list(action))

    add_entity = add_action


class DeclareLaunchArgument(Entity):
    """A launch argument. `py_type` is the Python type of a SimpleLauncher raw default."""

    def __init__(
        self,
        name: str,
        *,
        default_value: SubValue = None,
        description: str | None = None,
        choices: Iterable[str] | None = None,
        condition: Condition | None = None,
        py_type: str | None = None,
        **_: Any,
    ) -> None:
        self._init_entity(condition)
        if not isinstance(name, str) or not name:
            raise DslError(f"argument name must be a non-empty string, got {name!r}", self.origin)
        self.name = name
        self.default_value = default_value
        self.description = description
        self.choices = [str(c) for c in choices] if choices is not None else None
        self.py_type = py_type

    def describe(self) -> str:
        return f"argument {self.name}"


def pair_list(value: Any, what: str, origin: Origin | None = None) -> list[tuple[Any, Any]]:
    """Remappings, launch and xacro arguments: a dict or (key, value) pairs, as pairs."""
    if value is None:
        return []
    if isinstance(value, dict):
        return list(value.items())
    pairs: list[tuple[Any, Any]] = []
    try:
        items = list(value)
    except TypeError:
        items = [value]
    for item in items:
        if isinstance(item, dict):
            pairs.extend(item.items())
        elif isinstance(item, list | tuple) and len(item) == 2:
            pairs.append((item[0], item[1]))
        else:
            raise DslError(f"{what} must be a dict or (key, value) pairs, got {item!r}",
                           origin or caller_origin())
    return pairs
