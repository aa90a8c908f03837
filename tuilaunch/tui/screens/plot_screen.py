"""A live plot of a topic's numeric fields: the Topics tab's `p`, and `tuilaunch plot`.

Drawn by textual-plotext (plotext's braille line plots in a Textual widget): the curve of
each field over the window (10 s, 60 s, 5 min: `w`), its colour, last, min and max beside
it, the y range following the data. `space` pauses (the points keep coming, the picture
stays), `f` picks the fields among the topic's numeric ones. Imported only when a plot
is first shown: plotext costs 20 ms and memory nobody else needs.

The points come from the session server's `plot` events (engine/ros/plot/streams.py), already
decimated; the screen repaints at most REPAINT_HZ a second, and only when they changed.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen, Screen
from textual.widgets import Footer, SelectionList, Static
from textual_plotext import PlotextPlot

from ...client.plot_series import WINDOWS, PlotSeries, rebinned

REPAINT_HZ = 2.0
"""Repaints a second at most: a curve needs no more, a terminal over ssh gets little."""
COLOURS = ("cyan", "magenta", "green", "yellow", "red", "blue", "white")
"""The fields' colours, by position: names both plotext and Rich know."""
Ask = Callable[[list[str], int], None]
"""`ask(fields, tag)`: the host asks the server to plot these fields as stream `tag`."""


def figure(value: float) -> str:
    """A value in at most 9 characters: the side column is narrow."""
    text = f"{value:.4g}"
    return text if len(text) <= 9 else f"{value:.2e}"


def window_text(seconds: float) -> str:
    return f"{seconds / 60:g} min" if seconds >= 60 and seconds % 60 == 0 and seconds > 60 \
        else f"{seconds:g} s"


class FieldPicker(ModalScreen[list[str] | None]):
    """The topic's numeric fields, the plotted ones ticked: space ticks, enter plots."""

    DEFAULT_CSS = """
    FieldPicker { align: center middle; }
    FieldPicker > Vertical { width: 60; max-width: 100%; height: 80%; padding: 0 1;
                             border: round $primary; background: $surface; }
    FieldPicker SelectionList { height: 1fr; }
    FieldPicker #pick-help { height: 1; color: $text-muted; }
    """
    # enter before the list's own (which ticks, as space does)
    BINDINGS = [Binding("enter", "done", "Plot", priority=True),
                Binding("escape", "cancel", "Cancel")]

    def __init__(self, fields: list[str], chosen: list[str]) -> None:
        super().__init__()
        self.fields = fields
        self.chosen = chosen

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static("space: tick a field, enter: plot the ticked ones", id="pick-help")
            yield SelectionList[str](*[(f, f, f in self.chosen) for f in self.fields])

    def action_done(self) -> None:
        picked = list(self.query_one(SelectionList).selected)
        self.dismiss([f for f in self.fields if f in picked] or None)

    def action_cancel(self) -> None:
        self.dismiss(None)


class PlotScreen(Screen[None]):
    DEFAULT_CSS = """
    PlotScreen #plot-head { height: 1; padding: 0 1; background: $panel; }
    PlotScreen #plot-body { height: 1fr; }
    PlotScreen PlotextPlot { width: 1fr; }
    PlotScreen #plot-side { width: 24; padding: 0 1; }
    """
    BINDINGS = [
        Binding("w", "window", "Window", tooltip="10 s, 60 s, 5 min"),
        Binding("space", "pause", "Pause"),
        Binding("f", "fields", "Fields", tooltip="Pick the fields to plot"),
        Binding("q,escape", "leave", "Back"),
    ]

    def __init__(self, topic: str, type_name: str, numeric: list[str], fields: list[str],
                 ask: Ask | None, leave: Callable[[], None], tag: int = 1) -> None:
        """`fields`: plotted now (asked for as stream `tag`); `ask`: None when the fields
        cannot change (no picker); `leave()`: the host stops the stream and closes."""
        super().__init__()
        self.topic = topic
        self.type_name = type_name
        self.numeric = numeric
        self.series = PlotSeries(fields, tag)
        self.ask = ask
        self.leave = leave
        self.window = WINDOWS[0]
        self.paused_at: float | None = None
        """The right end of the picture while paused."""
        self.dirty = True
        self.drawn: dict[str, tuple[float, float, float]] = {}
        """Each field's last, min and max as last drawn (the tests read them)."""

    def compose(self) -> ComposeResult:
        yield Static("", id="plot-head")
        with Horizontal(id="plot-body"):
            yield PlotextPlot()
            yield Static("", id="plot-side")
        yield Footer()

    def on_mount(self) -> None:
        self.set_interval(1.0 / REPAINT_HZ, self.repaint)
        self.repaint()

    # --- points ------------------------------------------------------------------------------

    def add(self, data: dict[str, Any]) -> None:
        """A `plot` event of the server's."""
        if self.series.add(data):
            self.dirty = True

    def set_fields(self, fields: list[str]) -> None:
        if self.ask is None or fields == self.series.fields:
            return
        tag = int(self.series.tag or 0) + 1
        self.series = PlotSeries(fields, tag)  # the server sends what it kept again
        self.dirty = True
        self.ask(fields, tag)

    # --- drawing -----------------------------------------------------------------------------

    def repaint(self) -> None:
        if not self.dirty:
            return
        self.dirty = False
        end = self.paused_at if self.paused_at is not None else self.series.newest()
        self._head()
        plot = self.query_one(PlotextPlot)
        plt = plot.plt
        plt.clear_data()
        plt.clear_figure()
        plt.xlim(-self.window, 0)
        plt.xlabel("s")
        side: list[Text] = []
        self.drawn = {}
        bins = max(plot.size.width * 2, 10)  # braille: two dots a column
        for index, path in enumerate(self.series.fields):
            colour = COLOURS[index % len(COLOURS)]
            side.append(Text.assemble(("■ ", colour), (path, "bold")))
            stats = None if end is None else self.series.stats(path, self.window, end)
            if stats is None or end is None:
                side.append(Text("  no value yet", style="dim"))
                continue
            self.drawn[path] = (stats.last, stats.low, stats.high)
            side.append(Text(f"  last {figure(stats.last)}"))
            side.append(Text(f"  min  {figure(stats.low)}"))
            side.append(Text(f"  max  {figure(stats.high)}"))
            xs, ys = rebinned(self.series.shown(path, self.window, end), end - self.window,
                              end, bins)
            plt.plot([x - end for x in xs], ys, color=colour, marker="braille")
        self.query_one("#plot-side", Static).update(Text("\n").join(side))
        plot.refresh()

    def _head(self) -> None:
        state = "paused (space)" if self.paused_at is not None else "live"
        self.query_one("#plot-head", Static).update(Text.assemble(
            (self.topic, "bold"), f"  {self.type_name}  ", f"{window_text(self.window)} (w)  ",
            (state, "reverse" if self.paused_at is not None else "")))

    # --- keys --------------------------------------------------------------------------------

    def action_window(self) -> None:
        self.window = WINDOWS[(WINDOWS.index(self.window) + 1) % len(WINDOWS)]
        self.dirty = True
        self.repaint()

    def action_pause(self) -> None:
        self.paused_at = self.series.newest() if self.paused_at is None else None
        self.dirty = True
        self.repaint()

    def action_fields(self) -> None:
        if self.ask is None:
            self.notify("the fields are the command's: tuilaunch plot NAME TOPIC FIELD ...",
                        title="plot")
            return
        self.app.push_screen(FieldPicker(self.numeric, self.series.fields), self._picked)

    def _picked(self, fields: list[str] | None) -> None:
        if fields:
            self.set_fields(fields)

    def action_leave(self) -> None:
        self.leave()

    def on_resize(self) -> None:
        self.dirty = True  # more columns: more bins
