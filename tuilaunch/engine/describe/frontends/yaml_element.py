"""One entity of a YAML launch file, and the marked mappings pyyaml builds for it."""

from __future__ import annotations

from typing import Any

from ...errors import DslError, Origin
from ..type_utils import TypeSpec, check_yaml_value
from .element import Element


class MarkedDict(dict[Any, Any]):
    """A YAML mapping with its own position and each key's."""

    origin: Origin
    positions: dict[str, Origin]


class YamlElement(Element):
    """A YAML entity: `{tag: {attributes..., children: [...]}}` or `{tag: [children]}`."""

    def __init__(self, tag: str, origin: Origin, body: Any,
                 positions: dict[str, Origin] | None = None) -> None:
        super().__init__(tag, origin)
        self.body = body
        self.positions = positions or {}
        self._children_read = False

    def attribute_names(self) -> list[str]:
        return [str(k) for k in self.body] if isinstance(self.body, dict) else []

    def raw(self, name: str) -> Any:
        if not isinstance(self.body, dict) or name not in self.body:
            return None
        self._read.add(name)
        return self.body[name]

    def nested(self, name: str) -> list[Element] | None:
        self._asked_nested.add(name)
        value = self.raw(name)
        if value is None:
            return None
        where = self.positions.get(name, self.origin)
        if isinstance(value, dict):
            value = [value]
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise DslError(f"{self.tag}.{name} must be a list of mappings "
                           f"(- name: ... value: ...), got {value!r}", where)
        found: list[Element] = [element_of(name, item, getattr(item, "origin", where))
                                for item in value]
        return found

    def children(self) -> list[Element]:
        self._children_read = True
        if isinstance(self.body, list):
            return child_elements(self.body, self.origin)
        if isinstance(self.body, dict):
            if "children" not in self.body:
                return []
            self._read.add("children")
            return child_elements(self.body["children"], self.positions.get("children",
                                                                              self.origin))
        if self.body is None:
            return []
        raise self.error(f"expected a list of actions or a mapping, got {self.body!r}")

    def unread_nested(self) -> list[str]:
        if isinstance(self.body, list) and not self._children_read and self.body:
            return ["children"]
        return []

    def position_of(self, name: str) -> Origin:
        return self.positions.get(name, self.origin)

    def example(self, name: str) -> str:
        return f"`{name}: ...`"

    def coerce(self, name: str, value: Any, data_type: TypeSpec, can_be_str: bool) -> Any:
        return check_yaml_value(value, data_type, can_be_str)


def element_of(tag: str, body: Any, origin: Origin) -> YamlElement:
    positions = body.positions if isinstance(body, MarkedDict) else {}
    return YamlElement(tag, origin, body, positions)


def child_elements(items: Any, origin: Origin) -> list[Element]:
    """A list of single-key mappings (`- node: {...}`) as elements."""
    if items is None:
        return []
    if not isinstance(items, list):
        raise DslError(f"expected a list of actions (- tag: ...), got {items!r}", origin)
    out: list[Element] = []
    for item in items:
        where = getattr(item, "origin", origin)
        if not isinstance(item, dict) or len(item) != 1:
            raise DslError("each action is a mapping with one key, its tag "
                           f"(- node: ...), got {item!r}", where)
        (tag, body), = item.items()
        key_origin = item.positions.get(str(tag), where) if isinstance(item, MarkedDict) \
            else where
        out.append(element_of(str(tag), body, key_origin))
    return out
