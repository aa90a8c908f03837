"""What the supervisor tells its consumers (the headless printer, the TUI, session clients).

Every event goes through `Supervisor.emit`: it is written to launch.log (but output, which
has its own log files) and handed to each consumer; plugins report through the same call.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from ..describe.python.launch_events import EventInfo


@dataclass
class Event:
    """What consumers (the headless printer, the TUI) are told."""

    kind: str  # started | output | exited | failed | respawning | log | shutdown | finished
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


@dataclass
class ProcessExited(Event):
    """A process's end (kind "exited"), with its cause. On the wire and in launch.log it is
    an "exited" event whose data says "requested" (asked or typed) and "typed"
    (protocol.event_to_dict / event_from_dict make one from the other)."""

    kind: str = "exited"
    cause: ExitCause = ExitCause.CLEAN

    @property
    def crashed(self) -> bool:
        """An end nobody asked for, with a signal or a non-zero status: a failure."""
        return self.cause is ExitCause.CRASHED

    @property
    def asked(self) -> bool:
        """Stopped by someone: a stop asked for, or a key typed into it."""
        return self.cause in (ExitCause.ASKED, ExitCause.TYPED)


LaunchEvent = EventInfo
"""What launch-file callbacks receive: `event.text`, `event.returncode`, `event.reason`."""


Consumer = Callable[[Event], None]


__all__ = ["Consumer", "Event", "ExitCause", "LaunchEvent", "ProcessExited"]
