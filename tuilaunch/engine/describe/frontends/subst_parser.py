"""`$(name arg ...)` substitutions in attribute values, read as launch's grammar reads them.

A value is text with substitutions in it. A substitution's arguments are separated by
spaces; an argument is text and substitutions glued together, or a quoted string ('...' or
"...") in which spaces are kept and substitutions still work. A backslash escapes the next
character (`\\$(` is a literal `$(`). Parsing happens when the file is loaded; performing
happens at resolve time, like every other substitution of the engine.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any

from ...errors import LaunchError, Origin
from .. import logic_substitutions as logic
from .. import ros_substitutions as ros_subs
from .. import substitutions as subs

Part = Any  # str | Substitution
_IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_-]*")
_ESCAPE = re.compile(r"\\(.)", re.DOTALL)


class SubstitutionSyntaxError(ValueError):
    """A malformed or unknown `$(...)`, with the character offset where it went wrong."""

    def __init__(self, message: str, offset: int) -> None:
        super().__init__(message)
        self.message = message
        self.offset = offset


def _unescape(text: str) -> str:
    return _ESCAPE.sub(r"\1", text)


def _merge(parts: list[Part]) -> list[Part]:
    out: list[Part] = []
    for part in parts:
        if isinstance(part, str) and out and isinstance(out[-1], str):
            out[-1] += part
        elif part != "":
            out.append(part)
    return out


def as_value(parts: list[Part]) -> Any:
    """Parts as one value: text, a single substitution, or their concatenation."""
    parts = _merge(parts)
    if not parts:
        return ""
    if len(parts) == 1:
        return parts[0]
    return subs.SimpleSubstitution(*parts)


def _args(parts_list: list[list[Part]]) -> list[Any]:
    return [as_value(parts) for parts in parts_list]


def _count(name: str, args: list[Any], low: int, high: int) -> None:
    if not low <= len(args) <= high:
        wanted = str(low) if low == high else f"{low} to {high}"
        raise ValueError(f"$({name}) takes {wanted} argument(s), got {len(args)}")


def _var(a: list[Any]) -> subs.Substitution:
    _count("var", a, 1, 2)
    return FrontendVariable(a[0], a[1] if len(a) > 1 else None)


def _env(a: list[Any]) -> subs.Substitution:
    _count("env", a, 1, 2)
    return subs.EnvironmentVariable(a[0], default_value=a[1] if len(a) > 1 else None)


def _optenv(a: list[Any]) -> subs.Substitution:
    # ROS 1's optenv: an unset variable reads as its default, or as nothing
    _count("optenv", a, 1, 2)
    return subs.EnvironmentVariable(a[0], default_value=a[1] if len(a) > 1 else "")


def _eval(a: list[Any]) -> subs.Substitution:
    _count("eval", a, 1, 2)
    modules: list[str] = []
    if len(a) > 1:
        if not isinstance(a[1], str):
            raise ValueError("$(eval) takes its modules as plain text: math,os")
        modules = [m.strip() for m in a[1].split(",") if m.strip()]
    return subs.PythonExpression(a[0], modules)


def _command(a: list[Any]) -> subs.Substitution:
    _count("command", a, 1, 2)
    return subs.Command(a[0], a[1] if len(a) > 1 else "fail")


def _fixed(name: str, count: int, make: Callable[..., subs.Substitution])\
        -> Callable[[list[Any]], subs.Substitution]:
    def build(a: list[Any]) -> subs.Substitution:
        _count(name, a, count, count)
        return make(*a)
    return build


def _any_count(name: str, make: Callable[..., subs.Substitution])\
        -> Callable[[list[Any]], subs.Substitution]:
    def build(a: list[Any]) -> subs.Substitution:
        if not a:
            raise ValueError(f"$({name}) takes at least one argument")
        return make(*a)
    return build


def _param(a: list[Any]) -> subs.Substitution:
    _count("param", a, 1, 2)
    return ros_subs.ParameterSubstitution(a[0], a[1] if len(a) > 1 else None)


def _if(a: list[Any]) -> subs.Substitution:
    _count("if", a, 2, 3)
    return logic.IfElseSubstitution(a[0], a[1], a[2] if len(a) > 2 else "")


SUBSTITUTIONS: dict[str, Callable[[list[Any]], subs.Substitution]] = {
    "var": _var,
    "env": _env,
    "optenv": _optenv,
    "find-pkg-share": _fixed("find-pkg-share", 1, ros_subs.FindPackageShare),
    "find-pkg-prefix": _fixed("find-pkg-prefix", 1, ros_subs.FindPackagePrefix),
    "find-exec": _fixed("find-exec", 1, lambda n: subs.FindExecutable(name=n)),
    "exec-in-pkg": _fixed("exec-in-pkg", 2, ros_subs.ExecutableInPackage),
    "eval": _eval,
    "command": _command,
    "anon": _fixed("anon", 1, subs.AnonName),
    "dirname": _fixed("dirname", 0, subs.ThisLaunchFileDir),
    "filename": _fixed("filename", 0, subs.ThisLaunchFile),
    "file-content": _fixed("file-content", 1, subs.FileContent),
    "not": _fixed("not", 1, logic.NotSubstitution),
    "and": _fixed("and", 2, logic.AndSubstitution),
    "or": _fixed("or", 2, logic.OrSubstitution),
    "all": _any_count("all", logic.AndSubstitution),
    "any": _any_count("any", logic.OrSubstitution),
    "equals": _fixed("equals", 2, logic.EqualsSubstitution),
    "not-equals": _fixed("not-equals", 2, logic.NotEqualsSubstitution),
    "if": _if,
    "param": _param,
}


class _Reader:
    """Recursive descent over one attribute value."""

    def __init__(self, text: str, origin: Origin | None) -> None:
        self.text = text
        self.pos = 0
        self.origin = origin

    def at_substitution(self) -> bool:
        return self.text.startswith("$(", self.pos)

    def template(self, quote: str | None) -> list[Part]:
        """Text and substitutions up to the end (or up to the closing quote)."""
        return self._scan(quote or "", quote)

    def _scan(self, stops: str, quote: str | None) -> list[Part]:
        """Text and substitutions up to one of `stops` (or the end); a backslash escapes
        the next character."""
        parts: list[Part] = []
        start = self.pos
        while self.pos < len(self.text):
            char = self.text[self.pos]
            if char == "\\" and self.pos + 1 < len(self.text):
                self.pos += 2
                continue
            if self.at_substitution():
                parts.append(_unescape(self.text[start:self.pos]))
                parts.append(self.substitution(quote))
                start = self.pos
                continue
            if char in stops:
                break
            self.pos += 1
        parts.append(_unescape(self.text[start:self.pos]))
        return _merge(parts)

    def substitution(self, quote: str | None) -> subs.Substitution:
        begin = self.pos
        self.pos += 2
        match = _IDENTIFIER.match(self.text, self.pos)
        if match is None:
            raise SubstitutionSyntaxError("expected a substitution name after '$('", self.pos)
        name = match.group()
        self.pos = match.end()
        arguments: list[list[Part]] = []
        while True:
            if self.pos >= len(self.text):
                raise SubstitutionSyntaxError(f"$({name} ... is not closed with ')'", begin)
            char = self.text[self.pos]
            if char == ")":
                self.pos += 1
                break
            if char != " ":
                raise SubstitutionSyntaxError(
                    f"unexpected {char!r} in $({name} ...): arguments are separated by "
                    "spaces; quote an argument that holds spaces or parentheses", self.pos)
            while self.pos < len(self.text) and self.text[self.pos] == " ":
                self.pos += 1
            if self.pos < len(self.text) and self.text[self.pos] == ")":
                continue
            arguments.append(self.argument(quote))
        build = SUBSTITUTIONS.get(name)
        if build is None:
            raise SubstitutionSyntaxError(
                f"unknown substitution $({name}); known: {', '.join(sorted(SUBSTITUTIONS))}",
                begin)
        try:
            made = build(_args(arguments))
        except ValueError as exc:
            raise SubstitutionSyntaxError(str(exc), begin) from None
        made.origin = self.origin
        return made

    def argument(self, quote: str | None) -> list[Part]:
        char = self.text[self.pos]
        if quote is None and char in "'\"":
            opening = self.pos
            self.pos += 1
            quoted = self.template(char)
            if self.pos >= len(self.text):
                raise SubstitutionSyntaxError(f"quote {char} is not closed", opening)
            self.pos += 1
            return quoted or [""]
        return self._scan(" ()" + (quote or "'\""), quote)


def parse_substitutions(text: str, origin: Origin | None = None) -> list[Part]:
    """Text and substitution objects; raises SubstitutionSyntaxError for a bad `$(...)`."""
    reader = _Reader(text, origin)
    return reader.template(None)


def parse_value(text: str, origin: Origin | None = None) -> Any:
    """One attribute value: plain text stays text, otherwise a (concatenated) substitution."""
    return as_value(parse_substitutions(text, origin))


def has_substitution(text: str) -> bool:
    return "$(" in text


class FrontendVariable(subs.LaunchConfiguration):
    """`$(var name)`: a LaunchConfiguration whose hint speaks XML/YAML."""

    def perform(self, context: subs.PerformContext) -> str:
        try:
            return super().perform(context)
        except LaunchError as exc:
            name = self.name(context)
            raise LaunchError(exc.message, exc.origin,
                              hint=f'declare it with <arg name="{name}" default="..."/> '
                              f"or pass {name}:=value") from None
