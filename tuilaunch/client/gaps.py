"""Where a client's view of each log file stands, and the gaps in it read back through the
server: the lines a reconnection missed, and the lines of a pane shown again that were not
sent while another was shown (a `view` switch). Lines are counted from the log files'
sizes at the last subscription, so none is seen twice or missed.

RemoteSupervisor holds one; `read` is its connection's `call` (a ReadLog answered before
the next message is handled).
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Iterable
from typing import Any

from ..engine.run.events import Dropped, Event
from ..engine.run.session.log_reader import LogLine
from ..engine.run.vocabulary.requests import ReadLog

Reader = Callable[[ReadLog], Awaitable[dict[str, Any]]]


def shown(process: str, only: str | None) -> bool:
    return only is None or process == only


class Gaps:
    """The offsets and counts of one client's stream, and what its gaps hold."""

    def __init__(self, scrollback: int = 5000) -> None:
        self.scrollback = scrollback
        # the size of each log file at subscription, and the lines received (or dropped
        # for it) since
        self.start: dict[str, int] = {}
        self.received: dict[str, int] = {}
        self.last_event = 0.0  # the time of the latest state event received
        self.stream_only: str | None = None  # the pane shown as of the last event received
        self.hidden: dict[str, int] = {}
        """Processes not shown, and the byte of their log file from which their lines were
        not sent: read from there when they are shown again."""
        # output lines received on this connection, and on the ones before it: a line's
        # number in the stream (its event's data "line"), by which its stamp is read
        self.lines_here = 0
        self.lines_before = 0

    def subscribed(self, offsets: dict[str, int]) -> None:
        """A new subscription: lines count from these sizes."""
        self.lines_before += self.lines_here
        self.lines_here = 0
        self.start = dict(offsets)
        self.received = {}

    def count(self, process: str, lines: int) -> None:
        self.received[process] = self.received.get(process, 0) + lines

    def number(self, lines: int) -> int:
        """The stream's number of the first of `lines` output lines just received."""
        first = self.lines_before + self.lines_here
        self.lines_here += lines
        return first

    def where(self, process: str) -> dict[str, int]:
        """Where the next lines of `process` are in its log file, as a `dropped` event's
        data says (`read_log`'s start and skip): after what this client has been sent."""
        return {"start": self.start.get(process, 0), "skip": self.received.get(process, 0)}

    def heard(self, recent: Iterable[dict[str, Any]]) -> None:
        for data in recent:
            self.last_event = max(self.last_event, float(data.get("time") or 0.0))

    async def _page(self, read: Reader, process: str, start: int, end: int, skip: int,
                    lines: dict[str, list[LogLine]], notes: list[Event]) -> None:
        page = await read(ReadLog(process=process, start=start, skip=skip, end=end,
                                  limit=self.scrollback, tail=True))
        lines[process] = [LogLine(*line) for line in page["lines"]]
        if page.get("skipped"):  # read back only the last `scrollback` of them
            notes.append(Dropped(process, code=int(page["skipped"]),
                                 data={"start": start, "skip": skip}))

    async def missed(self, start: dict[str, int], received: dict[str, int],
                     offsets: dict[str, int], read: Reader,
                     ) -> tuple[dict[str, list[LogLine]], list[Event]]:
        """After a reconnection (subscribed again at `offsets`): the lines each shown log
        file got since the last line received on the connection before (counted from its
        `start` and `received`), and a Dropped note for those past the scrollback."""
        lines: dict[str, list[LogLine]] = {}
        notes: list[Event] = []
        for process, end in offsets.items():
            begin, skip = start.get(process, 0), received.get(process, 0)
            if not shown(process, self.stream_only) or end <= begin:
                continue  # a pane not shown is read from its file when it is
            await self._page(read, process, begin, end, skip, lines, notes)
        return lines, notes

    async def switched(self, only: str | None, offsets: dict[str, int],
                       processes: Iterable[str], read: Reader,
                       ) -> tuple[dict[str, list[LogLine]], list[Event]]:
        """A `view` event: from here the stream carries `only`'s lines; `offsets` are the
        log files' sizes at that instant. The lines of a pane shown again that were not
        sent, read from its file."""
        before, self.stream_only = self.stream_only, only
        lines: dict[str, list[LogLine]] = {}
        notes: list[Event] = []
        for process in sorted(set(offsets) | set(processes)):
            end = offsets.get(process, 0)
            if not shown(process, only):
                if shown(process, before):
                    self.hidden[process] = end  # its lines from here stay over there
                continue
            if shown(process, before) and process not in self.hidden:
                continue  # shown all along: its lines came as events
            begin = self.hidden.pop(process, 0)
            if end > begin:
                await self._page(read, process, begin, end, 0, lines, notes)
            # everything up to `end` is now here; its events from the stream come after it
            self.start[process], self.received[process] = end, 0
        return lines, notes
