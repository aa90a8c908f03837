"""One tag of an XML or YAML launch file, as launch's frontends read it.

Both formats offer the same three things to the walker: typed attributes, nested entities
under a name (`<param>` in a `<node>`, `param:` lists in YAML) and child actions. XML
attributes are text coerced to the type asked for (YAML rules when no type is given); YAML
values already carry their type. Every read is recorded so that an attribute or a nested tag
nobody read is reported as an error, as launch does, with the file, line and column.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from typing import Any

from ...errors import DslError, Origin
from ..type_utils import TypeSpec, coerce_text, type_name


class Element:
    """A tag with its attributes, nested entities and position."""

    tag: str
    origin: Origin

    def __init__(self, tag: str, origin: Origin) -> None:
        self.tag = tag
        self.origin = origin
        self._read: set[str] = set()
        self._read_nested: set[str] = set()
        self._asked: set[str] = set()  # every attribute the tag's parser looked for
        self._asked_nested: set[str] = set()

    @property
    def line_origin(self) -> Origin:
        """Where the entity was written, as entities show it (`file:line`)."""
        return Origin(self.origin.file, self.origin.line)

    def error(self, message: str, hint: str | None = None, at: str | None = None) -> DslError:
        """An error about this tag, placed at attribute or nested tag `at` when given."""
        where = self.origin if at is None else self.position_of(at)
        return DslError(f"{self.label}: {message}", where, hint=hint)

    # --- to implement per format ------------------------------------------------------

    def attribute_names(self) -> list[str]:
        raise NotImplementedError

    def raw(self, name: str) -> Any:
        """The attribute's value as written (None when absent), marking it read."""
        raise NotImplementedError

    def nested(self, name: str) -> list[Element] | None:
        """Nested entities called `name` (`List[Entity]` in launch), marking them read."""
        raise NotImplementedError

    def children(self) -> list[Element]:
        """The actions inside (a group's, a timer's, the root's)."""
        raise NotImplementedError

    def unread_nested(self) -> list[str]:
        raise NotImplementedError

    def coerce(self, name: str, value: Any, data_type: TypeSpec, can_be_str: bool) -> Any:
        raise NotImplementedError

    # --- shared -------------------------------------------------------------------------

    def has(self, name: str) -> bool:
        return name in self.attribute_names()

    def get(self, name: str, data_type: TypeSpec = "str", *, optional: bool = False,
            can_be_str: bool = True) -> Any:
        """An attribute read as launch's `Entity.get_attr` reads it."""
        self._asked.add(name)
        value = self.raw(name)
        if value is None:
            if optional:
                return None
            raise self.error(f"attribute '{name}' is required",
                             hint=f"add {self.example(name)} to {self.label}")
        try:
            return self.coerce(name, value, data_type, can_be_str)
        except ValueError as exc:
            raise self.error(f"attribute '{name}' = {value!r} is not {type_name(data_type)}"
                             f" ({exc})", at=name) from None

    def check_complete(self, advice: Mapping[str, str] | None = None) -> None:
        """Attributes and nested tags nobody read are mistakes: name them, and what fits.

        `advice` gives, for an attribute launch is known to refuse (ROS 1's `ns`), what to
        write instead; it takes the place of the closest-name guess."""
        unread = [n for n in self.attribute_names() if n not in self._read]
        takes = sorted(self._asked) + [f"<{n}>" for n in sorted(self._asked_nested)]
        hint = f"{self.label} takes {', '.join(takes)}" if takes else None
        if unread:
            advice = advice or {}
            guesses = [f"{n} ({advice[n]})" if n in advice
                       else f"{n} (did you mean {close[0]}?)" if close else n
                       for n in sorted(unread)
                       for close in [difflib.get_close_matches(
                           n, [*self._asked, *self._asked_nested], 1)]]
            raise DslError(f"{self.label}: unexpected attribute(s): {', '.join(guesses)}",
                           self.position_of(sorted(unread)[0]), hint=hint)
        nested = sorted(set(self.unread_nested()))
        if nested:
            guesses = [f"<{n}> (did you mean <{close[0]}>?)" if close else f"<{n}>"
                       for n in nested
                       for close in [difflib.get_close_matches(n, self._asked_nested, 1)]]
            raise DslError(f"{self.label}: unexpected nested tag(s): {', '.join(guesses)}",
                           self.position_of(nested[0]), hint=hint)

    @property
    def label(self) -> str:
        return f"<{self.tag}>"

    def position_of(self, name: str) -> Origin:
        """Where an attribute or nested tag was written, as closely as the format tells."""
        return self.origin

    def example(self, name: str) -> str:
        """How an attribute is written in this format, for hints."""
        return f'{name}="..."'

    def mark_read(self, name: str) -> None:
        self._read.add(name)


class XmlElement(Element):
    """An XML tag: attributes are text; `value-sep` splits `value` into a list."""

    def __init__(self, tag: str, origin: Origin, attributes: dict[str, str],
                 elements: list[XmlElement]) -> None:
        super().__init__(tag, origin)
        self.attributes = attributes
        self.elements = elements
        self.attribute_origins: dict[str, Origin] = {}

    def attribute_names(self) -> list[str]:
        return list(self.attributes)

    def raw(self, name: str) -> Any:
        if name not in self.attributes:
            return None
        self._read.add(name)
        separator = self.attributes.get(name + "-sep")
        if separator is not None:
            self._read.add(name + "-sep")
            if separator == "":
                raise self.error(f"attribute '{name}-sep' is empty", at=name + "-sep")
            return self.attributes[name].split(separator)
        return self.attributes[name]

    def nested(self, name: str) -> list[Element] | None:
        self._asked_nested.add(name)
        found: list[Element] = [e for e in self.elements if e.tag == name]
        if not found:
            return None
        self._read_nested.add(name)
        return found

    def children(self) -> list[Element]:
        self._read_nested.update(e.tag for e in self.elements)
        return list(self.elements)

    def unread_nested(self) -> list[str]:
        return [e.tag for e in self.elements if e.tag not in self._read_nested]

    def position_of(self, name: str) -> Origin:
        if name in self.attribute_origins:
            return self.attribute_origins[name]
        return next((e.origin for e in self.elements if e.tag == name), self.origin)

    def coerce(self, name: str, value: Any, data_type: TypeSpec, can_be_str: bool) -> Any:
        if isinstance(value, list):
            return [coerce_text(item, _item_type(data_type), can_be_str) for item in value]
        return coerce_text(value, data_type, can_be_str)


def _item_type(data_type: TypeSpec) -> TypeSpec:
    if isinstance(data_type, str) and data_type.startswith("list_of_"):
        return data_type[len("list_of_"):]
    return data_type
