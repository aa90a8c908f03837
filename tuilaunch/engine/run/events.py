"""What the supervisor tells its consumers (the headless printer, the TUI, session clients).

Every event goes through `Supervisor.emit`: it is written to launch.log (but output, which
has its own log files) and handed to each consumer; plugins report through the same call.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
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


LaunchEvent = EventInfo
"""What launch-file callbacks receive: `event.text`, `event.returncode`, `event.reason`."""


Consumer = Callable[[Event], None]


__all__ = ["Consumer", "Event", "LaunchEvent"]
