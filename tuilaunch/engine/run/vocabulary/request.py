"""A request of the session protocol as a class, and the one place requests become JSON and
back: `to_message` (what a client writes), `from_message` (what a server reads).

Each request is a frozen dataclass (requests.py, ros_requests.py) that names its op once,
`class Status(Request[StatusReply], op="status")`: the class is registered under its op
here, as events.py's `event_of` finds an event's class by its kind, and a server dispatches
on the class. The wire stays JSON lines, `{"id": n, "op": ..., field: value, ...}`: a field
left at its default is not written (the server reads an absent field as that default; a
default of None means "the server's own"), so the messages are those of the protocol's
earlier, untyped clients.

`Request[R]`: R is what the reply's result is read as (`reply(result)`): JSON for most, a
`str` for `find`, a bool for `transition`, and when R is a dataclass (`status`'s
StatusReply, status.py), that dataclass: the server writes it with `reply_to_json` and a
client reads it with `reply_from_json`, both here. A key the reply's class does not know
(a newer server's) is left out, a field the reply lacks takes its default.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Callable, Iterator, Mapping
from typing import Any, ClassVar, Generic, TypeVar

from ...errors import LaunchError

R = TypeVar("R")
T = TypeVar("T")


class _Registry(Mapping[str, "type[Request[Any]]"]):
    """The request classes by op, complete whenever it is read: a module of requests made
    on demand (requests.py's ROS inspector's requests, `later`) is imported on the first
    read, so that a launch nobody inspects does not pay for their classes at start. Every
    read goes through the three methods below (Mapping builds get, in, keys... on them)."""

    def __init__(self) -> None:
        self._classes: dict[str, type[Request[Any]]] = {}
        self._pending: list[Callable[[], object]] = []

    def later(self, load: Callable[[], object]) -> None:
        """`load` imports more requests (they register themselves): run before a read."""
        self._pending.append(load)

    def _load(self) -> dict[str, type[Request[Any]]]:
        while self._pending:
            self._pending.pop()()
        return self._classes

    def register(self, op: str, cls: type[Request[Any]]) -> None:
        known = self._classes.get(op)
        if known is not None:
            raise TypeError(f"two requests with op {op!r}: {known.__name__}, {cls.__name__}")
        self._classes[op] = cls

    def __getitem__(self, op: str) -> type[Request[Any]]:
        return self._load()[op]

    def __iter__(self) -> Iterator[str]:
        return iter(self._load())

    def __len__(self) -> int:
        return len(self._load())


REGISTRY = _Registry()
REQUESTS: Mapping[str, type[Request[Any]]] = REGISTRY
"""Every request class, by its op."""


class UnknownRequest(ValueError):
    """A message whose op no request class has, or whose fields do not fit it: one line for
    the reply's error."""


class Request(Generic[R]):
    """One request of the session protocol; subclasses are dataclasses naming their `op`,
    and `changes` when a read-only client must refuse them (how the refusal names it)."""

    op: ClassVar[str]
    changes: ClassVar[str | None] = None
    reply_type: ClassVar[type | None] = None
    """R when it is a dataclass: the reply is read as one (`reply_from_json`)."""

    def __init_subclass__(cls, op: str = "", changes: str | None = None,
                          **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if not op:
            return
        REGISTRY.register(op, cls)
        cls.op = op
        cls.changes = changes
        cls.reply_type = _dataclass_reply(cls)

    def reply(self, result: Any) -> R:
        """The reply's result, as this request's answer is read."""
        if self.reply_type is not None:
            return typing.cast(R, reply_from_json(self.reply_type, result))
        return typing.cast(R, result)


def _dataclass_reply(cls: type) -> type | None:
    """The R of `class X(Request[R], ...)` when R is a dataclass (the bases are evaluated
    as the class is made, whatever `from __future__ import annotations` says)."""
    for base in getattr(cls, "__orig_bases__", ()):
        if typing.get_origin(base) is Request:
            (reply,) = typing.get_args(base)
            return reply if isinstance(reply, type) and dataclasses.is_dataclass(reply) \
                else None
    return None


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


# --- replies -------------------------------------------------------------------------------


class MalformedReply(LaunchError):
    """A reply that cannot be read as its request's reply type: one line saying why."""


ABSENT_WHEN_NONE = "absent_when_none"


def absent_when_none(unless: Callable[[Any], bool] | None = None) -> dict[str, Any]:
    """A reply field's metadata, `field(default=None, metadata=absent_when_none())`: the
    field is left out of the JSON while None (as the untyped server wrote it only when it
    knew it), unless `unless(reply)`."""
    return {ABSENT_WHEN_NONE: unless or (lambda _reply: False)}


def reply_to_json(reply: Any) -> Any:
    """A reply as the wire writes it: a dataclass as an object of its fields in their order
    (one `absent_when_none` left out while None), its lists and dicts item by item."""
    if dataclasses.is_dataclass(reply) and not isinstance(reply, type):
        written: dict[str, Any] = {}
        for field in dataclasses.fields(reply):
            value = getattr(reply, field.name)
            unless = field.metadata.get(ABSENT_WHEN_NONE)
            if value is None and unless is not None and not unless(reply):
                continue
            written[field.name] = reply_to_json(value)
        return written
    if isinstance(reply, list | tuple):
        return [reply_to_json(item) for item in reply]
    if isinstance(reply, dict):
        return {key: reply_to_json(item) for key, item in reply.items()}
    return reply


def reply_from_json(cls: type[T], data: Any) -> T:
    """A reply's JSON read as the dataclass `cls`: each field by its name, a nested
    dataclass (also in a list, a dict's values or as an optional field) read the same way,
    anything else taken as sent. A key `cls` does not know (a newer server's) is ignored; a
    field the JSON lacks takes its default; MalformedReply when it has none, or when the
    JSON is not an object."""
    name = cls.__name__
    if not isinstance(data, dict):
        raise MalformedReply(f"a {name} must be an object, not {data!r}")
    hints = _reply_hints(cls)
    values: dict[str, Any] = {}
    for field in dataclasses.fields(cls):  # type: ignore[arg-type]
        if field.name in data:
            values[field.name] = _read(hints[field.name], data[field.name], name)
        elif field.default is dataclasses.MISSING and \
                field.default_factory is dataclasses.MISSING:
            raise MalformedReply(f"a {name} needs {field.name}")
    return cls(**values)


_REPLY_HINTS: dict[type, dict[str, Any]] = {}


def _reply_hints(cls: type) -> dict[str, Any]:
    """Each field's annotation, evaluated once per reply class."""
    hints = _REPLY_HINTS.get(cls)
    if hints is None:
        hints = _REPLY_HINTS[cls] = typing.get_type_hints(cls)
    return hints


def _read(hint: Any, value: Any, reply: str) -> Any:
    """One value of a reply as its annotation says, where that is a dataclass's."""
    if value is None:
        return None
    args = typing.get_args(hint)
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        kinds = [a for a in args if a is not type(None)]
        return _read(kinds[0], value, reply) if len(kinds) == 1 else value
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return reply_from_json(hint, value)
    origin = typing.get_origin(hint)
    if origin is list and args and isinstance(value, list):
        return [_read(args[0], item, reply) for item in value]
    if origin is dict and len(args) == 2 and isinstance(value, dict):
        return {key: _read(args[1], item, reply) for key, item in value.items()}
    return value


__all__ = ["REQUESTS", "MalformedReply", "Request", "UnknownRequest", "absent_when_none",
           "from_message", "reply_from_json", "reply_to_json", "to_message"]
