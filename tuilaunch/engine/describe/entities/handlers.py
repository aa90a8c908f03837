"""Event handlers (launch.event_handlers): actions run when a process starts, exits or
prints, when the launch shuts down; and RegisterEventHandler, which puts one in place."""

from __future__ import annotations

from collections.abc import Callable
from enum import StrEnum
from typing import Any

from ...errors import DslError
from ..conditions import Condition
from .base import Entity


class TriggerOn(StrEnum):
    """What a trigger waits for: the kind of an event handler, of a `When`, of a plan's
    Trigger. A StrEnum: the plan's JSON and launch.log say its value."""

    START = "start"  # OnProcessStart, When(node, OnProcessStart)
    EXIT = "exit"  # OnProcessExit, OnExecutionComplete, Node(on_exit=...)
    IO = "io"  # OnProcessIO: a line on stdout, stderr (or stdin)
    TIMER = "timer"  # TimerAction, When(delay=...): counted from the launch or an event
    SHUTDOWN = "shutdown"  # OnShutdown
    STATE = "state"  # launch_ros's OnStateTransition: a lifecycle node reaches a state


class EventHandler(Entity):
    """launch.event_handlers.*: actions run when a process starts, exits, prints, ..."""

    on: TriggerOn

    def __init__(self, target_action: Any = None, handler: Any = None, io: str | None = None)\
            -> None:
        self._init_entity(None)
        self.target = target_action
        self.handler = handler
        self.io = io


class OnProcessStart(EventHandler):
    on = TriggerOn.START

    def __init__(self, *, target_action: Any = None, on_start: Any = None, **_: Any) -> None:
        super().__init__(target_action, on_start)


class OnProcessExit(EventHandler):
    on = TriggerOn.EXIT

    def __init__(self, *, target_action: Any = None, on_exit: Any = None, **_: Any) -> None:
        super().__init__(target_action, on_exit)


class OnExecutionComplete(EventHandler):
    on = TriggerOn.EXIT

    def __init__(self, *, target_action: Any = None, on_completion: Any = None, **_: Any)\
            -> None:
        super().__init__(target_action, on_completion)


class OnProcessIO(EventHandler):
    on = TriggerOn.IO

    def __init__(self, *, target_action: Any = None, on_stdin: Any = None,
                 on_stdout: Any = None, on_stderr: Any = None, **_: Any) -> None:
        io = "stdout" if on_stdout is not None else "stderr" if on_stderr is not None else "stdin"
        super().__init__(target_action, on_stdout or on_stderr or on_stdin, io)


class OnShutdown(EventHandler):
    on = TriggerOn.SHUTDOWN

    def __init__(self, *, on_shutdown: Any = None, **_: Any) -> None:
        super().__init__(None, on_shutdown)


class RegisterEventHandler(Entity):
    def __init__(self, event_handler: EventHandler, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        if not isinstance(event_handler, EventHandler):
            raise DslError(
                f"RegisterEventHandler needs an event handler, got {event_handler!r}", self.origin
            )
        self.handler = event_handler


class IoCallbacks(Entity):
    """Python callbacks of an OnProcessIO group, called with each output event at run time."""

    def __init__(self, callbacks: list[Callable[[Any], Any]], launcher: Any = None) -> None:
        self._init_entity(None)
        self.callbacks = callbacks
        self.launcher = launcher
