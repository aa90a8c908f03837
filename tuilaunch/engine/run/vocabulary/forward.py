"""`Forward`: a read-only attribute that is a part's own, read through its holder
(RemoteSupervisor's `states` is its SessionState's `states`, a Link's `info` its
Connection's): one typed line where a property would take three to say the same.
"""

from __future__ import annotations

from typing import Any, Generic, TypeVar, overload

T = TypeVar("T")


class Forward(Generic[T]):
    """`states = Forward[dict[str, str]]("state")`: `obj.states` reads `obj.state.states`
    (`name`: the part's attribute when it is named otherwise). Never set through."""

    def __init__(self, part: str, name: str | None = None, doc: str | None = None) -> None:
        self.part = part
        self.name = name or ""
        self.__doc__ = doc

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = self.name or name

    @overload
    def __get__(self, obj: None, owner: type | None = None) -> Forward[T]: ...

    @overload
    def __get__(self, obj: object, owner: type | None = None) -> T: ...

    def __get__(self, obj: object | None, owner: type | None = None) -> Any:
        if obj is None:
            return self
        return getattr(getattr(obj, self.part), self.name)

    def __set__(self, obj: object, value: T) -> None:
        # as a property without a setter: the part's to change, never shadowed here
        raise AttributeError(f"{self.name} is {self.part}'s: set it there")
