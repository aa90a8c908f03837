"""The events launch hands to handlers: `ProcessExited`, `ProcessIO`, `Shutdown`, ...

Handlers written for launch read `event.returncode`, `event.text`, `event.action`,
`event.reason` and test `isinstance(event, ProcessExited)`; the supervisor builds these.
"""

from __future__ import annotations

from typing import Any


class Event:
    """launch.Event: the base of every event. A subclass's `name` is where launch defines
    it, `module`.ClassName, unless it says otherwise (`named=`, or a `name` of its own)."""

    name = "launch.Event"
    module = "launch.events"

    def __init_subclass__(cls, named: str | None = None, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        if "name" not in cls.__dict__:
            cls.name = f"{cls.module}.{named or cls.__name__}"


class EventInfo(Event):
    """One event with every field a handler may read; the subclasses say which kind."""

    name = "launch.Event"

    def __init__(self, process_name: str | None = None, pid: int | None = None,
                 text: bytes = b"", returncode: int | None = None, reason: str = "",
                 action: Any = None, cmd: list[str] | None = None) -> None:
        self.process_name = process_name
        self.pid = pid
        self.text = text
        self.returncode = returncode
        self.reason = reason
        self.action = action
        self.cmd = cmd or []
        self.cwd: str | None = None
        self.env: dict[str, str] | None = None
        self.due_to_sigint = False

    @property
    def execution_name(self) -> str | None:
        return self.process_name


class RunningProcessEvent(EventInfo):
    module = "launch.events.process"


class ProcessStarted(RunningProcessEvent):
    """launch.events.process.ProcessStarted."""


class ProcessExited(RunningProcessEvent):
    """launch.events.process.ProcessExited."""


class ProcessIO(RunningProcessEvent):
    fd = 1


class ProcessStdout(ProcessIO):
    """launch.events.process.ProcessStdout."""


class ProcessStderr(ProcessIO):
    fd = 2


class ProcessStdin(ProcessIO):
    fd = 0


class ProcessTargetedEvent(Event):
    module = "launch.events.process"

    def __init__(self, *, process_matcher: Any = None) -> None:
        self.process_matcher = process_matcher


class ExecutionComplete(EventInfo):
    """launch.events.ExecutionComplete."""


class ShutdownEvent(EventInfo, named="Shutdown"):
    """launch.events.Shutdown."""


class TimerEvent(EventInfo):
    """launch.events.TimerEvent."""


def event_for(on: str, stream: str | None = None, **fields: Any) -> EventInfo:
    """The event object of a kind of trigger (`start`, `exit`, `io`, `shutdown`, ...)."""
    kind: type[EventInfo] = {
        "start": ProcessStarted, "exit": ProcessExited, "shutdown": ShutdownEvent,
        "timer": TimerEvent,
    }.get(on, EventInfo)
    if on == "io":
        kind = {"stderr": ProcessStderr, "stdin": ProcessStdin}.get(stream or "", ProcessStdout)
    return kind(**fields)
