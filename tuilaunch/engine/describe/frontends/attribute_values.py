"""An attribute's value as the walker reads it: its `$(...)` substitutions parsed, typed when
asked, split into a command line, or read as nested name/value pairs."""

from __future__ import annotations

import shlex
from typing import Any

from .element import Element
from .subst_parser import Part, SubstitutionSyntaxError, as_value, parse_substitutions


def parse(element: Element, name: str, raw: Any) -> Any:
    """Substitutions in a value read from `name` (text only; typed values stay)."""
    if isinstance(raw, list):
        return [parse(element, name, item) for item in raw]
    if not isinstance(raw, str):
        return raw
    return as_value(parts(element, name, raw))

def parts(element: Element, name: str, raw: str) -> list[Part]:
    try:
        return parse_substitutions(raw, element.position_of(name))
    except SubstitutionSyntaxError as exc:
        raise element.error(f"attribute '{name}': {exc.message} "
                            f"(at character {exc.offset + 1} of {raw!r})",
                            at=name) from None

def text(element: Element, name: str, optional: bool = False) -> Any:
    raw = element.get(name, optional=optional)
    return None if raw is None else parse(element, name, raw)

def typed(element: Element, name: str, data_type: str) -> Any:
    """A typed attribute that may also be a substitution (`can_be_str`)."""
    raw = element.get(name, data_type, optional=True, can_be_str=True)
    return None if raw is None else parse(element, name, raw)

def command_line(element: Element, name: str, raw: str) -> list[Any]:
    """Space-separated arguments; a substitution glued to text stays one argument."""
    args: list[list[Part]] = []
    current: list[Part] = []
    for part in parts(element, name, raw):
        if not isinstance(part, str):
            current.append(part)
            continue
        try:
            tokens = shlex.split(part)
        except ValueError as exc:
            raise element.error(f"attribute '{name}': {exc} in {raw!r}", at=name) from None
        if not tokens:
            if current:
                args.append(current)
            current = []
            continue
        if part[0].isspace() and current:
            args.append(current)
            current = []
        current.append(tokens[0])
        if len(tokens) > 1:
            args.append(current)
            args.extend([token] for token in tokens[1:-1])
            current = [tokens[-1]]
        if part[-1].isspace():
            args.append(current)
            current = []
    if current:
        args.append(current)
    return [as_value(arg) for arg in args]

def pairs(element: Element, tag: str, first: str, second: str)\
        -> list[tuple[Any, Any]] | None:
    nested = element.nested(tag)
    if nested is None:
        return None
    out = [(text(item, first), text(item, second)) for item in nested]
    for item in nested:
        item.check_complete()
    return out
