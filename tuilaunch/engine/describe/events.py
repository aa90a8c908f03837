"""`simple_launch.events`: `When(node, OnProcessStart, delay)` and the event classes."""

from __future__ import annotations

from typing import Any

from ..errors import DslError, caller_origin
from .entities import (
    OnExecutionComplete,
    OnProcessExit,
    OnProcessIO,
    OnProcessStart,
    OnShutdown,
    TriggerOn,
)

__all__ = [
    "OnExecutionComplete",
    "OnProcessExit",
    "OnProcessIO",
    "OnProcessStart",
    "OnShutdown",
    "When",
]

_KINDS: dict[type, TriggerOn] = {
    OnProcessStart: TriggerOn.START,
    OnProcessExit: TriggerOn.EXIT,
    OnExecutionComplete: TriggerOn.EXIT,
    OnProcessIO: TriggerOn.IO,
    OnShutdown: TriggerOn.SHUTDOWN,
}


class When:
    """A trigger for a group: an event on a reference action, then an optional delay."""

    def __init__(self, action: Any = None, event: Any = None, delay: Any = None,
                 io: str | None = None) -> None:
        self.origin = caller_origin()
        self.target = action
        self.delay = delay
        self.io = io
        self.on: TriggerOn
        if event is None:
            self.on = TriggerOn.TIMER
            if delay is None:
                raise DslError("When() needs an event, a delay, or both", self.origin)
            return
        kind = _KINDS.get(event) if isinstance(event, type) else None
        if kind is None:
            raise DslError(
                f"When() cannot handle event {event!r}",
                self.origin,
                hint="use OnProcessStart, OnProcessExit, OnExecutionComplete, OnProcessIO or "
                "OnShutdown from simple_launch.events",
            )
        self.on = kind
        if kind == "shutdown":
            self.target = None
        elif action is None:
            raise DslError(f"When(event={event.__name__}) needs the action to watch", self.origin)
        if kind == "io" and io not in ("stdin", "stdout", "stderr"):
            raise DslError(
                "When(..., OnProcessIO) needs io='stdout', 'stderr' or 'stdin'", self.origin
            )
