"""A request of the session protocol as a class, and the one place requests become JSON and
back: `to_message` (what a client writes), `from_message` (what a server reads).

Each request is a frozen dataclass (requests.py, ros_requests.py) that names its op once,
`class Status(Request[dict[str, Any]], op="status")`: the class is registered under its op
here, as events.py's `event_of` finds an event's class by its kind, and a server dispatches
on the class. The wire stays JSON lines, `{"id": n, "op": ..., field: value, ...}`: a field
left at its default is not written (the server reads an absent field as that default; a
default of None means "the server's own"), so the messages are those of the protocol's
earlier, untyped clients.

`Request[R]`: R is what the reply's result is read as (`reply(result)`): JSON for most, a
`str` for `find`, a bool for `transition`.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Callable, Iterator
from typing import Any, ClassVar, Generic, TypeVar

R = TypeVar("R")

class _Registry(dict[str, "type[Request[Any]]"]):
    """The request classes by op, complete whenever it is read: a module of requests made
    on demand (requests.py's ROS inspector's requests, `later`) is imported on the first
    read, so that a launch nobody inspects does not pay for their classes at start."""

    def __init__(self) -> None:
        super().__init__()
        self._pending: list[Callable[[], object]] = []

    def later(self, load: Callable[[], object]) -> None:
        """`load` imports more requests (they register themselves): run before a read."""
        self._pending.append(load)

    def _load(self) -> None:
        while self._pending:
            self._pending.pop()()

    def register(self, op: str, cls: type[Request[Any]]) -> None:
        if dict.__contains__(self, op):
            known = dict.__getitem__(self, op)
            raise TypeError(f"two requests with op {op!r}: {known.__name__}, {cls.__name__}")
        dict.__setitem__(self, op, cls)

    def __getitem__(self, op: str) -> type[Request[Any]]:
        self._load()
        return super().__getitem__(op)

    def get(self, op: str, default: Any = None) -> Any:
        self._load()
        return super().get(op, default)

    def __contains__(self, op: object) -> bool:
        self._load()
        return super().__contains__(op)

    def __iter__(self) -> Iterator[str]:
        self._load()
        return super().__iter__()

    def __len__(self) -> int:
        self._load()
        return super().__len__()

    def keys(self) -> Any:
        self._load()
        return super().keys()

    def values(self) -> Any:
        self._load()
        return super().values()

    def items(self) -> Any:
        self._load()
        return super().items()


REGISTRY = _Registry()
REQUESTS: dict[str, type[Request[Any]]] = REGISTRY
"""Every request class, by its op."""


class UnknownRequest(ValueError):
    """A message whose op no request class has, or whose fields do not fit it: one line for
    the reply's error."""


class Request(Generic[R]):
    """One request of the session protocol; subclasses are dataclasses naming their `op`,
    and `changes` when a read-only client must refuse them (how the refusal names it)."""

    op: ClassVar[str]
    changes: ClassVar[str | None] = None

    def __init_subclass__(cls, op: str = "", changes: str | None = None,
                          **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if not op:
            return
        REGISTRY.register(op, cls)
        cls.op = op
        cls.changes = changes

    def reply(self, result: Any) -> R:
        """The reply's result, as this request's answer is read."""
        return typing.cast(R, result)


def to_message(request: Request[Any], request_id: int | None = None) -> dict[str, Any]:
    """The request as the wire writes it: its op, its id, and the fields not at their
    default."""
    message: dict[str, Any] = {} if request_id is None else {"id": request_id}
    message["op"] = request.op
    for field in dataclasses.fields(request):  # type: ignore[arg-type]
        value = getattr(request, field.name)
        if field.default is not dataclasses.MISSING and value == field.default:
            continue
        if field.default_factory is not dataclasses.MISSING and \
                value == field.default_factory():
            continue
        message[field.name] = value
    return message


def from_message(message: dict[str, Any]) -> Request[Any]:
    """The request a message asks (its other keys, "id" and the server's "client", are not
    the request's). UnknownRequest, one line naming the op and the field, when no request
    has that op or a field is missing or of the wrong kind."""
    asked = message.get("op")
    cls = REQUESTS.get(asked) if isinstance(asked, str) else None
    if cls is None:
        raise UnknownRequest(f"unknown request {asked!r}")
    op = cls.op
    fields: dict[str, Any] = {}
    for field in dataclasses.fields(cls):  # type: ignore[arg-type]
        if field.name not in message:
            if field.default is dataclasses.MISSING and \
                    field.default_factory is dataclasses.MISSING:
                raise UnknownRequest(f"request {op} needs {field.name}")
            continue
        fields[field.name] = _coerced(op, field.name, _hints(cls)[field.name],
                                      message[field.name])
    return cls(**fields)


_HINTS: dict[str, dict[str, Any]] = {}


def _hints(cls: type[Request[Any]]) -> dict[str, Any]:
    """Each field's annotation, evaluated once per class."""
    hints = _HINTS.get(cls.op)
    if hints is None:
        hints = _HINTS[cls.op] = typing.get_type_hints(cls)
    return hints


_SCALARS = (bool, int, float, str)


def _coerced(op: str, name: str, hint: Any, value: Any) -> Any:
    """A field's value as its annotation says: a number sent as text read as one; None only
    where the field may be None. Containers and Any are taken as sent (their handlers check
    their items)."""
    args = typing.get_args(hint)
    optional = isinstance(hint, types.UnionType) and type(None) in args
    base = next((a for a in args if a is not type(None)), Any) if optional else hint
    if value is None:
        if optional or base is Any:
            return None
        raise UnknownRequest(f"request {op} needs {name}")
    if base in _SCALARS:
        if base is bool:
            return bool(value)
        try:
            return base(value)
        except (TypeError, ValueError):
            raise UnknownRequest(f"request {op}: {name} must be {base.__name__}, not "
                                 f"{value!r}") from None
    origin = typing.get_origin(base) or base
    if origin in (list, dict) and not isinstance(value, origin):
        kind = "a list" if origin is list else "an object"
        raise UnknownRequest(f"request {op}: {name} must be {kind}, not {value!r}")
    return value


__all__ = ["REQUESTS", "Request", "UnknownRequest", "from_message", "to_message"]
