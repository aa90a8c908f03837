"""A machine's share of a placed launch (`--share MACHINE`): what it answers the
launching side beyond the usual session requests.

The share runs only the processes placed on its machine (run/supervisor/placed.py); the launching
side tells it when the others start and exit (`external_event`), so a node here can wait
for one elsewhere, and asks it for the lines its nodes printed while no link was there to
carry them (`share_lines`, read from its log files).
"""

from __future__ import annotations

import collections
from collections.abc import Callable
from typing import Any

from ..plugins import Handlers, Plugin
from ..session.log_reader import LogLine, read_lines
from ..supervisor.supervisor import Supervisor
from ..vocabulary.requests import ExternalEvent, ShareLines

BACKFILL_LINES = 2000
"""Lines of a process sent at most per request (the newest); older ones stay in the log
file there, and the launching side says how many."""


class ShareSide(Plugin):
    """A machine's share: hears what happens to the processes other machines run."""

    def __init__(self, supervisor: Supervisor, machine: str) -> None:
        self.supervisor = supervisor
        self.seen: set[tuple[Any, ...]] = set()  # the coordinator repeats them on reconnect
        supervisor.set_placement(machine, None)

    def handlers(self, find_process: Callable[[str], str]) -> Handlers:
        async def external_event(request: ExternalEvent, client: int) -> Any:
            key = (request.process, request.on, request.pid, request.code)
            if key not in self.seen:
                self.seen.add(key)
                self.supervisor.external_event(request.process, request.on, request.pid,
                                               request.code)
            return {}

        async def share_lines(request: ShareLines, client: int) -> Any:
            process = find_process(request.process)
            start, end, skip = request.start, request.end, request.skip
            kept: collections.deque[LogLine] = collections.deque(maxlen=BACKFILL_LINES)
            count = 0
            for index, line in enumerate(
                    read_lines(self.supervisor.log_dir / f"{process}.log", end, start)):
                if index >= skip:
                    kept.append(line)
                    count += 1
            return {"lines": [[line.time, line.stream, line.text] for line in kept],
                    "skipped": count - len(kept)}

        return {ExternalEvent: external_event, ShareLines: share_lines}


__all__ = ["BACKFILL_LINES", "ShareSide"]
