"""What the supervisor tells its consumers (the headless printer, the TUI, session clients).

Every event goes through `Supervisor.emit`: it is written to launch.log (but output, which
has its own log files) and handed to each consumer; plugins report through the same call.

Each kind of event is a class of its own (`Started`, `Output`, `ProcessExited`, ...), and
consumers dispatch on the class (`isinstance`, `match`). `kind` stays a field because it is
what the wire (session/protocol.py) and launch.log say; `event_of` makes the class back from
it. A kind no class knows (a newer server's, behind the protocol version) stays an `Event`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from ...describe.python.launch_events import EventInfo


@dataclass
class Event:
    """What consumers (the headless printer, the TUI) are told."""

    kind: str  # the class's own in every subclass: what the wire and launch.log say
    process: str | None = None
    pid: int | None = None
    stream: str | None = None
    lines: list[str] = field(default_factory=list)
    code: int | None = None
    reason: str | None = None
    level: str = "INFO"
    time: float = field(default_factory=time.time)
    data: dict[str, Any] | None = None  # lifecycle state or component result details


class ExitCause(StrEnum):
    """Why a process ended, decided once where it ended (supervisor/starting.py), read by
    every consumer (the tree, headless, the exit status, `logs`, a placed launch's mirror)."""

    CLEAN = "clean"  # status 0, nobody asked
    ASKED = "asked"  # a stop asked for: the operator, `tuilaunch stop`, a restart, shutdown
    TYPED = "typed"  # a ctrl+c (or ctrl+\\, ctrl+z) typed into it by the operator
    CRASHED = "crashed"  # a signal or a non-zero status nobody asked for

    @staticmethod
    def of(code: int, requested: bool, typed: bool = False) -> ExitCause:
        if typed:
            return ExitCause.TYPED
        if requested:
            return ExitCause.ASKED
        return ExitCause.CLEAN if code == 0 else ExitCause.CRASHED


# Each class's `kind` is its own and never passed: the first argument is then its process.

# --- a process's (or an action's) life: the tree's states ----------------------------------

@dataclass
class Started(Event):
    """A process started (its pid), or an action began (no pid): its state is "running"."""

    kind: str = field(default="started", init=False)


@dataclass
class Failed(Event):
    """A process that could not start (or whose machine could not be reached): "failed"."""

    kind: str = field(default="failed", init=False)


@dataclass
class Stopping(Event):
    """A stop of a running process began (an operator's, a restart's, the launch's end): it
    is "stopping" until its ProcessExited. Told once per stop, whoever asked for it."""

    kind: str = field(default="stopping", init=False)


@dataclass
class Respawning(Event):
    """A crashed process waits to come back: data has its "try" and "delay" (seconds)."""

    kind: str = field(default="respawning", init=False)


@dataclass
class ActionFinished(Event):
    """An action of the plan ended: reason is its state ("done" or "failed")."""

    kind: str = field(default="finished", init=False)


@dataclass
class LifecycleChanged(Event):
    """A lifecycle node reached a state: reason is its label ("active"), data its id."""

    kind: str = field(default="lifecycle", init=False)


@dataclass
class ComponentReport(Event):
    """A component loaded into (or refused by) a container: data says which and where."""

    kind: str = field(default="component", init=False)


# --- what is said ----------------------------------------------------------------------------

@dataclass
class Output(Event):
    """Lines a process (or a placed launch's other side) wrote on `stream`."""

    kind: str = field(default="output", init=False)


@dataclass
class Log(Event):
    """A line of the launch's own (a LogInfo, a stop's signal, a notice) at `level`."""

    kind: str = field(default="log", init=False)


@dataclass
class Dropped(Event):
    """`code` lines of `process` a client was not sent (a flood); its log file has them."""

    kind: str = field(default="dropped", init=False)


@dataclass
class Shutdown(Event):
    """The launch's shutdown began, for `reason`."""

    kind: str = field(default="shutdown", init=False)


@dataclass
class Relaunched(Event):
    """The launch runs a new plan (a relaunch after an edit): lines say what changed."""

    kind: str = field(default="relaunched", init=False)


@dataclass
class Typing(Event):
    """A client typed into `process` (data: which client): the others see who types."""

    kind: str = field(default="typing", init=False)


@dataclass
class View(Event):
    """The session server's answer to a client that chose what it shows (protocol.py)."""

    kind: str = field(default="view", init=False)


# --- what a client asked to watch: sent to that client only, data is the reading -----------

@dataclass
class Reading(Event):
    """A reading a client asked for (an inspector's stream); each kind its own class."""


@dataclass
class Rates(Reading):
    kind: str = field(default="rates", init=False)


@dataclass
class Hz(Reading):
    kind: str = field(default="hz", init=False)


@dataclass
class Echo(Reading):
    kind: str = field(default="echo", init=False)


@dataclass
class PlotSamples(Reading):
    kind: str = field(default="plot", init=False)


@dataclass
class Qos(Reading):
    kind: str = field(default="qos", init=False)


@dataclass
class Resources(Reading):
    kind: str = field(default="resources", init=False)


@dataclass
class Trend(Reading):
    kind: str = field(default="trend", init=False)


@dataclass
class ProcessExited(Event):
    """A process's end (kind "exited"), with its cause. On the wire and in launch.log it is
    an "exited" event whose data says "requested" (asked or typed) and "typed"
    (protocol.event_to_dict / event_from_dict make one from the other)."""

    kind: str = field(default="exited", init=False)
    cause: ExitCause = ExitCause.CLEAN

    @property
    def crashed(self) -> bool:
        """An end nobody asked for, with a signal or a non-zero status: a failure."""
        return self.cause is ExitCause.CRASHED

    @property
    def asked(self) -> bool:
        """Stopped by someone: a stop asked for, or a key typed into it."""
        return self.cause in (ExitCause.ASKED, ExitCause.TYPED)


LIVE_STATES = ("running", "stopping")
"""The states of a process that runs (has a pid, can be typed into), a stop begun or not."""

STATE_EVENTS = (Started, Failed, Stopping, Respawning, ProcessExited)
"""The events that change a process's state in the tree."""


def _subclasses(cls: type[Event]) -> list[type[Event]]:
    found = []
    for sub in cls.__subclasses__():
        found += [sub, *_subclasses(sub)]
    return found


EVENT_TYPES: dict[str, type[Event]] = {
    kind: sub for sub in _subclasses(Event)
    if isinstance(kind := getattr(sub, "kind", None), str)}  # Reading has none of its own
"""Each kind's class, by the kind the wire says."""


def event_of(kind: str, **fields: Any) -> Event:
    """The event of this kind, of its class (a ProcessExited is made with its cause by the
    caller); a kind no class knows stays a plain Event."""
    typed = EVENT_TYPES.get(kind)
    return Event(kind, **fields) if typed is None else typed(**fields)


LaunchEvent = EventInfo
"""What launch-file callbacks receive: `event.text`, `event.returncode`, `event.reason`."""


Consumer = Callable[[Event], None]


__all__ = ["EVENT_TYPES", "LIVE_STATES", "STATE_EVENTS", "ActionFinished", "ComponentReport",
           "Consumer", "Dropped", "Echo", "Event", "ExitCause", "Failed", "Hz", "LaunchEvent",
           "LifecycleChanged", "Log", "Output", "PlotSamples", "ProcessExited", "Qos", "Rates",
           "Reading", "Relaunched", "Resources", "Respawning", "Shutdown", "Started",
           "Stopping", "Trend", "Typing", "View", "event_of"]
