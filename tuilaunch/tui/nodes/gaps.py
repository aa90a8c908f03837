"""Reading back what a link did not send: a flood's lines kept off the screen, and the
ROS stamps of lines sent while no pane showed them.

Under a flood a display is sent what it can draw (over an ssh link, a pane's worth of lines
a second); the session says where each run of lines it did not send is in the process's
log file, and the pane shows a line standing for it. When the user scrolls back to that
line, its lines are read from the log file through the session (`read_log`, where the
nodes run), a thousand at a time, and take its place: scrolled back, nothing is missed,
and only what the user scrolls back to crosses the link.

Over a link, the lines also come without their ROS stamp while the pane shows neither the
time column nor the raw format: the server keeps the stamps, and they are read for the
lines held here before either is shown or the pane is saved or copied.

A save or copy (`w`, `y`) reads every gap of the pane whole first, so the file holds the
lines the pane stands for, not the lines standing for them (`read_whole`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ...client.port import LaunchPort
from ...engine.run.engine_thread import EngineThread
from ...engine.run.session.log_reader import READ_LOG_LIMIT
from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.requests import ReadLog
from ..output_store import Gap, Line, OutputStore, read_back
from ..screens.output_panel import GapsRead, OutputPanel

GAP_READ = 1000
"""Lines of a gap read at a time: a few screens to scroll through, and a small answer over
a link; the rest of a longer gap is read when the user scrolls on to it."""
EXPORT_MOST = 200_000
"""Lines of gaps read back for one save or copy at most (40 panes of scrollback, about
10 MB over the link): a pane a flood ran through for minutes stands for millions, which
`tuilaunch logs` gives better; those beyond are said, their marker left in place."""


class GapReader:
    """Reads a pane's gaps and missing stamps through the session's client (`port`, on
    the engine thread `engine`), into the store and the pane; `notify` says what failed."""

    def __init__(self, store: OutputStore, pane: OutputPanel, engine: Callable[[], EngineThread],
                 port: Callable[[], LaunchPort | None],
                 notify: Callable[..., Any]) -> None:
        self.store, self.pane = store, pane
        self._engine, self._port, self._notify = engine, port, notify
        pane.read_gaps = self.read_whole  # w and y read the gaps through this session

    async def read_gap(self, marker: Line, reading_up: bool) -> None:
        gap, port = marker.gap, self._port()
        if gap is None or port is None:
            return
        take = min(gap.count, GAP_READ)
        while True:
            # reading upwards, the gap's newest lines come first: those next to the lines
            # below
            skip = gap.skip + gap.count - take if reading_up else gap.skip
            try:
                page = await self._engine().run(port.request(ReadLog(process=marker.process,
                                                                     start=gap.start, skip=skip,
                                                                     limit=take)))
            except SessionError as exc:
                self.pane.gap_not_read(marker)  # asked again when next on screen
                self._notify(f"{marker.process}: the lines not drawn could not be read: "
                             f"{exc}", severity="warning")
                return
            rows = list(page.get("lines") or [])
            if not rows or len(rows) >= take:
                break
            # an answer carries a few MiB of text: of long lines, fewer than asked, the
            # first of them; upwards, those next to the lines below are asked for instead
            take = len(rows)
            if not reading_up:
                break
        if not rows:  # the file was removed or cut short meanwhile: the line says so
            self._notify(f"{marker.process}: its log file no longer has the lines not drawn "
                         "there", severity="warning")
            return
        left = gap.count - take
        rest = None if left <= 0 else Gap(gap.start, gap.skip, left) if reading_up else \
            Gap(gap.start, gap.skip + take, left)
        lines = self.store.fill_gap(marker, rows, rest, rest_first=reading_up)
        self.pane.fill_gap(marker, lines)

    async def read_whole(self, markers: list[Line]) -> GapsRead:
        """Every line of these gaps (oldest first), up to EXPORT_MOST in all, for a save or
        a copy; the pane is left as it is. What could not be read is counted, and why."""
        read = GapsRead()
        left_in_all = EXPORT_MOST
        for number, marker in enumerate(markers):
            gap, port = marker.gap, self._port()
            if gap is None:
                continue
            if port is None or left_in_all < gap.count:
                read.why = read.why or ("not connected" if port is None else
                                        f"more than {EXPORT_MOST} lines")
                read.unread += sum(m.gap.count for m in markers[number:] if m.gap)
                break
            try:
                rows = await self._gap_rows(port, marker.process, gap)
            except SessionError as exc:
                read.why = read.why or str(exc)
                read.unread += gap.count
                continue
            if len(rows) < gap.count:  # the file was removed or cut short meanwhile
                read.why = read.why or "its log file no longer has them"
                read.unread += gap.count
                continue
            read.lines[id(marker)] = read_back(marker.process, rows)
            left_in_all -= gap.count
        return read

    async def _gap_rows(self, port: LaunchPort, process: str, gap: Gap) -> list[list[Any]]:
        """A gap's `[time, stream, text]` rows, a page at a time (an answer carries at
        most READ_LOG_LIMIT lines and a few MiB: on from its `next` byte)."""
        rows: list[list[Any]] = []
        start, skip = gap.start, gap.skip
        while len(rows) < gap.count:
            page = await self._engine().run(port.request(ReadLog(
                process=process, start=start, skip=skip,
                limit=min(gap.count - len(rows), READ_LOG_LIMIT))))
            got = list(page.get("lines") or [])
            if not got:
                break
            rows += got
            start, skip = int(page.get("next") or start), 0
        return rows[:gap.count]

    def stamps_known(self, port: LaunchPort | None, shown: bool) -> bool:
        """Whether every line here has its stamp and the link sends them so (nothing to
        read): no link between, or one already sending what `shown` wants."""
        return port is None or (shown == port.stamps_shown and
                                self.store.unstamped.first() is None)

    async def read_stamps(self, port: LaunchPort,
                          shown: bool) -> tuple[int, int, dict[int, int]] | None:
        """The stamps of the lines held here without theirs (None: not read, said)."""
        try:
            first, end, stamps = await self._engine().run(
                port.read_stamps(shown, self.store.unstamped.first()))
        except Exception as exc:  # the link is down, or worse: the key still does its part
            self._notify(f"ROS stamps not read: {exc}. Lines that came without theirs show "
                         "when they arrived.", severity="warning")
            return None
        return first, end, stamps

    def fill_stamps(self, first: int, end: int, stamps: dict[int, int]) -> None:
        if self.store.unstamped.fill(first, end, stamps):
            self.pane.stamps_read()
