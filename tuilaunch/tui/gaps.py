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
"""

from __future__ import annotations

from textual import on

from ..client.port import LaunchPort
from ..engine.run.session.session_dir import SessionError
from .output_store import Gap, Line
from .screens.output_panel import OutputPanel
from .session_link import SessionLink

GAP_READ = 1000
"""Lines of a gap read at a time: a few screens to scroll through, and a small answer over
a link; the rest of a longer gap is read when the user scrolls on to it."""


class Gaps(SessionLink):
    @on(OutputPanel.GapShown)
    def _gap_shown(self, message: OutputPanel.GapShown) -> None:
        self.run_worker(self._read_gap(message.line, message.reading_up), group="gaps",
                        exit_on_error=False)

    async def _read_gap(self, marker: Line, reading_up: bool) -> None:
        gap = marker.gap
        if gap is None or self.supervisor is None:
            return
        take = min(gap.count, GAP_READ)
        # reading upwards, the gap's newest lines come first: those next to the lines below
        skip = gap.skip + gap.count - take if reading_up else gap.skip
        try:
            page = await self.engine.run(self.supervisor.request("read_log", process=marker.process,
                                                 start=gap.start, skip=skip, limit=take))
        except SessionError as exc:
            self.output_panel.gap_not_read(marker)  # asked again when next on screen
            self.notify(f"{marker.process}: the lines not drawn could not be read: {exc}",
                        severity="warning")
            return
        rows = list(page.get("lines") or [])
        if not rows:  # the file was removed or cut short meanwhile: the line says so
            self.notify(f"{marker.process}: its log file no longer has the lines not drawn "
                        "there", severity="warning")
            return
        left = gap.count - take
        rest = None if left <= 0 else Gap(gap.start, gap.skip, left) if reading_up else \
            Gap(gap.start, gap.skip + take, left)
        lines = self.store.fill_gap(marker, rows, rest, rest_first=reading_up)
        self.output_panel.fill_gap(marker, lines)

    @on(OutputPanel.StampsWanted)
    def _stamps_wanted(self, message: OutputPanel.StampsWanted) -> None:
        supervisor = self.over_link()
        if supervisor is None or (message.shown == supervisor.stamps_shown
                                  and self.store.unstamped.first() is None):
            message.then()  # every line here has its stamp, and the link sends them so
            return
        self.run_worker(self._read_stamps(supervisor, message), group="stamps",
                        exit_on_error=False)

    async def _read_stamps(self, supervisor: LaunchPort,
                           message: OutputPanel.StampsWanted) -> None:
        try:
            first, end, stamps = await self.engine.run(
                supervisor.read_stamps(message.shown, self.store.unstamped.first()))
        except Exception as exc:  # the link is down, or worse: the key still does its part
            self.notify(f"ROS stamps not read: {exc}. Lines that came without theirs show "
                        "when they arrived.", severity="warning")
        else:
            self.drain()  # the lines sent before the answer, in the store before it
            if self.store.unstamped.fill(first, end, stamps):
                self.output_panel.stamps_read()
        message.then()
