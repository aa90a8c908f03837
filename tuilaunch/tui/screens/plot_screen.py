"""A live plot of topic fields: the Topics tab's `p`, and `tuilaunch plot`.

Drawn by textual-plotext (plotext's braille line plots in a Textual widget): the curve of
each field over the window (10 s, 60 s, 5 min: `w`), its colour, last, min and max beside
it. Fields of several topics, of several sessions, share the plot (`a` adds a topic, `f`
picks the fields); fields of magnitudes too far apart to read on one axis get stacked
panels of their own (`y`: automatic, one axis, a panel per field); `t` switches the time
between arrival and the messages' header.stamp; `x` draws the first field against the
second (XY); `S` saves what the plot holds as CSV; `space` pauses. Imported only when a
plot is first shown: plotext costs 20 ms and memory nobody else needs.

The screen asks its host's sessions for the streams itself (`PlotHost.request`: the
session requests `plot`, `plot_stop`, `plot_fields`, `topics`), so the TUI, the fleet and
`tuilaunch plot` open a plot the same way: the host only hands it the `plot` events. The
points come already decimated (engine/ros/plot/streams.py); the screen repaints at most
REPAINT_HZ a second, and only when they changed.
"""

from __future__ import annotations

import time
from collections.abc import Awaitable
from pathlib import Path
from typing import Any, Protocol, TypeVar

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal
from textual.screen import Screen
from textual.widgets import Static
from textual_plotext import PlotextPlot

from ...client.inspect.plot_series import WINDOWS, PlotSeries, Source, rebinned
from ...client.inspect.plot_shapes import panels, series_csv, xy_pairs
from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.request import Request
from ...engine.run.vocabulary.requests import PlotFields, PlotStart, PlotStop, Topics
from ..textual_compat import Footer
from .plot_pickers import FieldPicker, TopicPicker

R = TypeVar("R")

REPAINT_HZ = 2.0
"""Repaints a second at most: a curve needs no more, a terminal over ssh gets little."""
COLOURS = ("cyan", "magenta", "green", "yellow", "red", "blue", "white")
"""The fields' colours, by position: names both plotext and Rich know."""
SCALES = ("auto", "one axis", "panels")
"""`y`: panels where magnitudes differ (auto), every field on one axis, a panel each."""
SIDE = 24
"""Columns of the legend beside the plot."""


class SessionPlots:
    """A PlotHost over sessions' requests: `requesters` by session name (`""` for the only
    one), each `await requester(request)`, as the TUI's `inspect` and a port's
    `request` run on the engine thread are; `leave()` closes the screen."""

    def __init__(self, requesters: dict[str, Any], leave: Any) -> None:
        self.requesters = requesters
        self.sessions = list(requesters)
        self._leave = leave

    def request(self, session: str, request: Request[R]) -> Awaitable[R]:
        requester = self.requesters.get(session)
        if requester is None:
            raise SessionError(f"no session {session} on this plot")
        result: Awaitable[R] = requester(request)
        return result

    def leave(self) -> None:
        self._leave()


class PlotHost(Protocol):
    """What a plot screen needs of whoever shows it: its sessions' requests, and leaving."""

    sessions: list[str]
    """The sessions it reaches, as the user names them (`""`: the only one)."""

    def request(self, session: str, request: Request[R]) -> Awaitable[R]:
        """A session request's result; SessionError with the session's one line."""
        ...

    def leave(self) -> None:
        """The screen is done (its streams were stopped)."""
        ...


def figure(value: float) -> str:
    """A value in at most 9 characters: the side column is narrow."""
    text = f"{value:.4g}"
    return text if len(text) <= 9 else f"{value:.2e}"


def window_text(seconds: float) -> str:
    return f"{seconds / 60:g} min" if seconds >= 60 and seconds % 60 == 0 and seconds > 60 \
        else f"{seconds:g} s"


def cut_left(text: str, width: int) -> str:
    """A column's name within `width`: its end (the field) is what tells it apart."""
    return text if len(text) <= width else "…" + text[-(width - 1):]


class PlotScreen(Screen[None]):
    DEFAULT_CSS = f"""
    PlotScreen #plot-head {{ height: 1; padding: 0 1; background: $panel; }}
    PlotScreen #plot-body {{ height: 1fr; }}
    PlotScreen PlotextPlot {{ width: 1fr; }}
    PlotScreen #plot-side {{ width: {SIDE}; padding: 0 1; }}
    """
    BINDINGS = [
        Binding("w", "window", "Window", tooltip="10 s, 60 s, 5 min"),
        Binding("space", "pause", "Pause"),
        Binding("f", "fields", "Fields", tooltip="Pick the fields to plot"),
        Binding("a", "add_topic", "Add", tooltip="Add a field of another topic"),
        Binding("t", "time", "Time", tooltip="Arrival time or the messages' header.stamp"),
        Binding("y", "scale", "Axes", tooltip="Panels where magnitudes differ, one axis, "
                "a panel per field"),
        Binding("x", "xy", "XY", tooltip="The first field against the second"),
        Binding("S", "save", "Save", tooltip="Save what the plot holds as CSV"),
        Binding("q,escape", "leave", "Back"),
    ]

    def __init__(self, host: PlotHost, sources: list[Source], stamp: bool = False,
                 started: bool = False, folder: Path | None = None) -> None:
        """`sources`: the topics plotted first; `started`: their streams are asked for
        already (`tuilaunch plot` checks the fields before the screen shows); `folder`:
        where `S` saves (the working directory)."""
        super().__init__()
        self.host = host
        self.series = PlotSeries(sources)
        self.stamp = stamp
        self.window = WINDOWS[0]
        self.scale = SCALES[0]
        self.xy = False
        self.folder = folder
        self.paused_at: float | None = None
        """The right end of the picture while paused."""
        self.dirty = True
        self.drawn: dict[str, tuple[float, float, float]] = {}
        """Each column's last, min and max as last drawn (the tests read them)."""
        self.groups: list[list[str]] = []
        """The panels as last drawn, the columns of each (the tests read them)."""
        self.saved: Path | None = None
        self.on_axis: list[str] = []
        """The columns on the time axis as last drawn (by header.stamp: the stamped)."""
        self._started = started

    def compose(self) -> ComposeResult:
        yield Static("", id="plot-head")
        with Horizontal(id="plot-body"):
            yield PlotextPlot()
            yield Static("", id="plot-side")
        yield Footer()

    def on_mount(self) -> None:
        self.set_interval(1.0 / REPAINT_HZ, self.repaint)
        if not self._started:
            for source in self.series.sources:
                self._ask(source)
        self.repaint()

    # --- streams -----------------------------------------------------------------------------

    def add(self, data: dict[str, Any]) -> None:
        """A `plot` event of the server's (of any session: the tag says whose)."""
        if self.series.add(data):
            self.dirty = True

    def _ask(self, source: Source) -> None:
        self.run_worker(self._asking(source), group="plot", exit_on_error=False)

    async def _asking(self, source: Source) -> None:
        try:
            answer = await self.host.request(source.session, PlotStart(
                topic=source.topic, fields=source.fields, tag=source.tag, stamp=self.stamp))
        except SessionError as exc:
            self.notify(str(exc), severity="error", title="plot")
            return
        source.type_name = str(answer.get("type") or "")
        source.stamped = bool(answer.get("stamped"))
        self.dirty = True

    async def _stopping(self, source: Source) -> None:
        try:
            await self.host.request(source.session, PlotStop(topic=source.topic))
        except SessionError:
            pass  # the session or its link went: the stream went with it

    def set_fields(self, fields: list[str], session: str | None = None,
                   topic: str | None = None) -> None:
        """Plots `fields` of a topic (the first plotted unless named): a new stream of it,
        or none when `fields` is empty (the topic leaves the plot)."""
        first = self.series.sources[0] if self.series.sources else None
        session = first.session if session is None and first is not None else session or ""
        topic = topic if topic is not None else first.topic if first is not None else ""
        old = self.series.find(session, topic)
        if old is not None and fields == old.fields:
            return
        if not fields:
            if old is not None:
                self.series.remove(old)
                self.run_worker(self._stopping(old), group="plot", exit_on_error=False)
        else:
            source = Source(session, topic, list(fields),
                            type_name=old.type_name if old else "",
                            stamped=old.stamped if old else False)
            self.series.put(source)  # the server sends what it kept again
            self._ask(source)
        self.dirty = True

    # --- drawing -----------------------------------------------------------------------------

    def repaint(self) -> None:
        if not self.dirty:
            return
        self.dirty = False
        columns = self.series.columns
        colours = {c: COLOURS[i % len(COLOURS)] for i, c in enumerate(columns)}
        # by header.stamp, a topic without one has another clock: listed, not drawn
        unstamped = [s for s in self.series.sources if self.stamp and not s.stamped]
        if len(unstamped) < len(self.series.sources):
            columns = [c for s in self.series.sources if s not in unstamped
                       for c in (self.series.column(s, p) for p in s.fields)]
        self.on_axis = columns
        end = self.paused_at if self.paused_at is not None else \
            self.series.newest(columns)
        self._head()
        plot = self.query_one(PlotextPlot)
        plt = plot.plt
        plt.clear_data()
        plt.clear_figure()
        side: list[Text] = []
        self.drawn = {}
        ranges: dict[str, tuple[float, float]] = {}
        for column in self.series.columns:
            side.append(Text.assemble(("■ ", colours[column]),
                                      (cut_left(column, SIDE - 4), "bold")))
            if column not in columns:
                side.append(Text("  no header.stamp", style="dim"))
                continue
            stats = None if end is None else self.series.stats(column, self.window, end)
            if stats is None:
                side.append(Text("  no value yet", style="dim"))
                continue
            self.drawn[column] = (stats.last, stats.low, stats.high)
            ranges[column] = (stats.low, stats.high)
            side.append(Text(f"  last {figure(stats.last)}"))
            side.append(Text(f"  min  {figure(stats.low)}"))
            side.append(Text(f"  max  {figure(stats.high)}"))
        if unstamped and len(unstamped) == len(self.series.sources):
            side.append(Text("no header.stamp: arrival time", style="dim"))
        self.query_one("#plot-side", Static).update(Text("\n").join(side))
        if end is not None and self.xy and len(columns) >= 2:
            self._draw_xy(plt, columns[0], columns[1], end)
        elif end is not None:
            self._draw_panels(plt, plot, columns, ranges, colours, end)
        else:
            plt.xlim(-self.window, 0)
        plot.refresh()

    def _draw_panels(self, plt: Any, plot: PlotextPlot, columns: list[str],
                     ranges: dict[str, tuple[float, float]], colours: dict[str, str],
                     end: float) -> None:
        if self.scale == "one axis":
            groups = [list(ranges)]
        elif self.scale == "panels":
            groups = [[c] for c in ranges]
        else:
            groups = panels(ranges)
        self.groups = [g for g in groups if g] or [[]]
        bins = max(plot.size.width * 2, 10)  # braille: two dots a column
        if len(self.groups) > 1:
            plt.subplots(len(self.groups), 1)
        for index, group in enumerate(self.groups):
            panel = plt.subplot(index + 1, 1) if len(self.groups) > 1 else plt
            panel.xlim(-self.window, 0)
            if index == len(self.groups) - 1:
                panel.xlabel("s" if not self.stamp else "s (header.stamp)")
            for column in group:
                xs, ys = rebinned(self.series.shown(column, self.window, end),
                                  end - self.window, end, bins)
                panel.plot([x - end for x in xs], ys, color=colours[column],
                           marker="braille")

    def _draw_xy(self, plt: Any, x_column: str, y_column: str, end: float) -> None:
        xs, ys = xy_pairs(self.series.shown(x_column, self.window, end),
                          self.series.shown(y_column, self.window, end))
        self.groups = [[x_column, y_column]]
        plt.xlabel(cut_left(x_column, 30))
        plt.ylabel(cut_left(y_column, 30))
        if xs:
            plt.plot(xs, ys, color=COLOURS[1], marker="braille")
            plt.scatter(xs[-1:], ys[-1:], color=COLOURS[0], marker="●")

    def _head(self) -> None:
        sources = self.series.sources
        if len(sources) == 1:
            what: list[Any] = [(sources[0].topic, "bold"), f"  {sources[0].type_name}  "]
        else:
            what = [(f"{len(sources)} topics", "bold"), "  "]
        paused = self.paused_at is not None
        # the axes said when not automatic; the time always: arrival unless asked
        mode = "XY  " if self.xy else "" if self.scale == "auto" else f"{self.scale}  "
        self.query_one("#plot-head", Static).update(Text.assemble(
            *what, f"{window_text(self.window)} (w)  ",
            "header.stamp" if self.stamp else "arrival", " (t)  ", mode,
            ("paused" if paused else "live", "reverse" if paused else "")))

    # --- keys --------------------------------------------------------------------------------

    def action_window(self) -> None:
        self.window = WINDOWS[(WINDOWS.index(self.window) + 1) % len(WINDOWS)]
        self.dirty = True
        self.repaint()

    def action_pause(self) -> None:
        self.paused_at = self.series.newest(self.on_axis) if self.paused_at is None \
            else None
        self.dirty = True
        self.repaint()

    def action_scale(self) -> None:
        self.scale = SCALES[(SCALES.index(self.scale) + 1) % len(SCALES)]
        self.xy = False
        self.dirty = True
        self.repaint()

    def action_xy(self) -> None:
        if not self.xy and len(self.series.columns) < 2:
            self.notify("XY draws the first field against the second: pick two (f, a)",
                        title="plot")
            return
        self.xy = not self.xy
        self.dirty = True
        self.repaint()

    def action_time(self) -> None:
        """Arrival time or header.stamp: every stream asked again (the server keeps the
        minutes of both), the points it sends replacing the ones held."""
        self.stamp = not self.stamp
        self.paused_at = None
        for source in list(self.series.sources):
            fresh = Source(source.session, source.topic, source.fields,
                           type_name=source.type_name, stamped=source.stamped)
            self.series.put(fresh)
            self._ask(fresh)
        self.dirty = True
        self.repaint()

    def action_save(self) -> None:
        text, rows = series_csv(self.series)
        name = time.strftime("plot-%Y%m%d-%H%M%S.csv")
        path = (self.folder or Path.cwd()) / name
        try:
            path.write_text(text)
        except OSError as exc:
            self.notify(f"not saved: {path}: {exc.strerror or exc}", severity="error",
                        title="plot")
            return
        self.saved = path
        self.notify(f"saved {rows} rows ({len(self.series.columns)} fields, "
                    f"{window_text(round(self.series.held()))}) to {path}", title="plot",
                    timeout=8)

    def action_fields(self) -> None:
        self.run_worker(self._pick_fields(), group="plot", exit_on_error=False)

    async def _pick_fields(self) -> None:
        items: list[tuple[Any, str]] = []
        chosen: list[Any] = []
        for source in self.series.sources:
            numeric = await self._numeric(source.session, source.topic)
            for path in numeric or source.fields:
                key = (source.session, source.topic, path)
                items.append((key, self.series.column(source, path)))
                if path in source.fields:
                    chosen.append(key)
        self.app.push_screen(FieldPicker(items, chosen), self._picked)

    async def _numeric(self, session: str, topic: str) -> list[str] | None:
        try:
            answer = await self.host.request(session, PlotFields(topic=topic))
        except SessionError as exc:
            self.notify(str(exc), severity="error", title="plot")
            return None
        return list(answer.get("fields") or [])

    def _picked(self, keys: list[Any] | None) -> None:
        if keys is None:
            return
        if not keys:
            self.notify("no field ticked: the plot stays as it was", title="plot")
            return
        wanted: dict[tuple[str, str], list[str]] = {}
        for session, topic, path in keys:
            wanted.setdefault((session, topic), []).append(path)
        for source in list(self.series.sources):
            self.set_fields(wanted.pop((source.session, source.topic), []), source.session,
                            source.topic)
        for (session, topic), paths in wanted.items():
            self.set_fields(paths, session, topic)

    def action_add_topic(self) -> None:
        self.run_worker(self._add_topic(), group="plot", exit_on_error=False)

    async def _add_topic(self) -> None:
        topics: list[tuple[str, str, str]] = []
        for session in self.host.sessions:
            try:
                answer = await self.host.request(session, Topics())
            except SessionError as exc:
                self.notify(str(exc), severity="error", title="plot")
                continue
            topics += [(session, t["name"], ", ".join(t.get("types") or []))
                       for t in answer.get("topics") or [] if t.get("publishers")]
        if not topics:
            self.notify("no topic is published", title="plot")
            return
        self.app.push_screen(TopicPicker(topics), self._topic_picked)

    def _topic_picked(self, chosen: tuple[str, str] | None) -> None:
        if chosen is not None:
            self.run_worker(self._pick_of(*chosen), group="plot", exit_on_error=False)

    async def _pick_of(self, session: str, topic: str) -> None:
        numeric = await self._numeric(session, topic)
        if numeric is None:
            return
        if not numeric:
            self.notify(f"{topic} has no numeric field to plot", title="plot")
            return
        old = self.series.find(session, topic)
        items = [((session, topic, path), path) for path in numeric]
        chosen = [(session, topic, p) for p in (old.fields if old else numeric[:1])]

        def picked(keys: list[Any] | None) -> None:
            if keys is not None:
                self.set_fields([path for _, _, path in keys], session, topic)

        self.app.push_screen(FieldPicker(items, chosen, f"{session} {topic}".strip()),
                             picked)

    def action_leave(self) -> None:
        for source in self.series.sources:  # the app's workers: the screen's go with it
            self.app.run_worker(self._stopping(source), group="plot", exit_on_error=False)
        self.host.leave()

    def on_resize(self) -> None:
        self.dirty = True  # more columns: more bins
