"""The events launch hands to handlers: `ProcessExited`, `ProcessIO`, `Shutdown`, ...

Handlers written for launch read `event.returncode`, `event.text`, `event.action`,
`event.reason` and test `isinstance(event, ProcessExited)`; the supervisor builds these.
"""

from __future__ import annotations

from typing import Any


class Event:
    """launch.Event: the base of every event."""

    name = "launch.Event"


class EventInfo(Event):
    """One event with every field a handler may read; the subclasses say which kind."""

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
    name = "launch.events.process.RunningProcessEvent"


class ProcessStarted(RunningProcessEvent):
    name = "launch.events.process.ProcessStarted"


class ProcessExited(RunningProcessEvent):
    name = "launch.events.process.ProcessExited"


class ProcessIO(RunningProcessEvent):
    name = "launch.events.process.ProcessIO"
    fd = 1


class ProcessStdout(ProcessIO):
    name = "launch.events.process.ProcessStdout"


class ProcessStderr(ProcessIO):
    name = "launch.events.process.ProcessStderr"
    fd = 2


class ProcessStdin(ProcessIO):
    name = "launch.events.process.ProcessStdin"
    fd = 0


class ProcessTargetedEvent(Event):
    name = "launch.events.process.ProcessTargetedEvent"

    def __init__(self, *, process_matcher: Any = None) -> None:
        self.process_matcher = process_matcher


class ExecutionComplete(EventInfo):
    name = "launch.events.ExecutionComplete"


class ShutdownEvent(EventInfo):
    name = "launch.events.Shutdown"


class TimerEvent(EventInfo):
    name = "launch.events.TimerEvent"


def event_for(on: str, stream: str | None = None, **fields: Any) -> EventInfo:
    """The event object of a kind of trigger (`start`, `exit`, `io`, `shutdown`, ...)."""
    kind: type[EventInfo] = {
        "start": ProcessStarted, "exit": ProcessExited, "shutdown": ShutdownEvent,
        "timer": TimerEvent,
    }.get(on, EventInfo)
    if on == "io":
        kind = {"stderr": ProcessStderr, "stdin": ProcessStdin}.get(stream or "", ProcessStdout)
    return kind(**fields)
