"""One record per process: what the supervisor keeps of a process besides its state (the
states, which every client is sent as they are, stay one dict) and its running child
(`core.running`, the process table). Its behaviours read and write the record; the
supervisor's read-only views (`exit_codes`, `deaths`, `coming_back`, `respawn_waits`) are
made from the records for the session server and the tests.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from typing import Any

from ..process.process_command import StartCommand


@dataclass
class ProcessRecord:
    """One process's facts, from its last start and end and from the operator's hands."""

    exit_code: int | None = None
    """Its last exit's status (negative: the signal)."""
    crash_code: int | None = None
    """Its last crash's status: an end nobody asked for, with a signal or non-zero."""
    crash_time: float | None = None
    """When it last crashed (monotonic), for the respawn policy and the stop's race."""
    respawn_wait: asyncio.Event | None = None
    """Set while it waits out its respawn delay; setting the event calls it off (a stop
    asked meanwhile: the node is between two runs, and it must not come back)."""
    coming_back: bool = False
    """Stopped to be started again (a restart; a relaunch that changed it): its exit is a
    step, marked `again` in its event, so a `tuilaunch wait ... running` waits on through
    it instead of taking it for the end."""
    prefix: str | None = None
    """An operator's tool (`gdb -q -ex run --args`) it runs under, from a `restart` with a
    prefix until the next restart without one."""
    terminal: bool = False
    """Restarted by an operator with a terminal (to type into one started without, as
    launch's default is): from that restart until the next plain one."""
    log_level: str | None = None
    """`--log-level` given at a restart, kept across respawns until a restart changes it."""
    started_with: StartCommand | None = None
    """Its last start, exactly (status's command line)."""
    death: dict[str, str] | None = None
    """A crash's `signal` name and `core` location, until it starts again."""


class ProcessRecords(dict[str, ProcessRecord]):
    """The records by process id; a process's is made when first asked for."""

    def __missing__(self, process_id: str) -> ProcessRecord:
        record = self[process_id] = ProcessRecord()
        return record

    def having(self, attribute: str) -> dict[str, Any]:
        """Each process whose record has `attribute` set (not None, not False)."""
        return {process: value for process, record in self.items()
                if (value := getattr(record, attribute)) is not None and value is not False}
