"""The Nodes tab as one widget: the detail line, and the group tree and the output pane of
the app's session view (session_view.py), which owns them and their behaviour.

The view shows each tick's events in the tree and pane (`SessionView.show_events`, at
once, with the status line the app updates in the same call); the tab then counts a
respawn's wait down and redraws its detail line (`batch_shown`). The tab reads a pane's
gaps and missing stamps through the session itself (`GapReader`), and draws the selected
row in full on the detail line, with its CPU and memory trend when the app has one
(`trend_of`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol

from rich.text import Text
from textual import events, on
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.message import Message
from textual.timer import Timer
from textual.widgets import Static, Tree

from ...client.port import LaunchPort
from ..output_store import Line, OutputStore
from ..screens.output_panel import NodesView, OutputPanel
from ..screens.tree_panel import LaunchTree, RowData, RowKind
from ..screens.units import short_bytes, spark
from .commands import SelectionCommands
from .events import Batch, NodeEvents
from .gaps import GapReader

TREND_WIDTH = 10
"""Columns of each sparkline (CPU, memory) at the end of the detail line."""
SCALE_WIDTH = 6
"""Columns of each sparkline's scale after it (its max: ` 12%`, ` 66M`)."""
NARROW = 70
"""Columns below which the tree goes above the pane (a phone's browser: about 42), as the
fleet's trees do (app.tcss: NodesTab.-narrow)."""


class StampsRead(Message, bubble=False):
    """Stamps read for the lines held without theirs: filled in after the events drained
    before the answer, which are in the tab's queue before this."""

    def __init__(self, first: int, end: int, stamps: dict[int, int],
                 then: Callable[[], None]) -> None:
        super().__init__()
        self.first, self.end, self.stamps, self.then = first, end, stamps, then


class TabSession(Protocol):
    """The session the tab shows (session_view.py's SessionView): its widgets and pieces."""

    tree: LaunchTree
    pane: OutputPanel
    store: OutputStore
    events: NodeEvents
    gaps: GapReader
    commands: SelectionCommands

    def over_link(self) -> LaunchPort | None: ...


class NodesTab(Vertical):
    """The tree, the detail line and the pane of one session."""

    def __init__(self, view: TabSession, drain: Callable[[], None],
                 id: str | None = None) -> None:
        """`drain`: takes the session's events waiting now, for the tab (as a message)."""
        super().__init__(id=id)
        self.view, self.drain = view, drain
        self.store = view.store
        # the view's: its tree and pane, how its events show in them, what a link did not
        # send read back, the selection's commands
        self.launch_tree, self.pane = view.tree, view.pane
        self.events, self.gaps, self.commands = view.events, view.gaps, view.commands
        self.trend_of: Callable[[str], Sequence[tuple[float, float]] | None] = lambda _: None
        """The selected process's (CPU%, RSS) samples, oldest first (the app's inspector
        sets it; None: not measured)."""
        self._detail_drawn: tuple[object, ...] | None = None
        self._countdown: Timer | None = None

    def compose(self) -> ComposeResult:
        yield Static("", id="detail")
        with NodesView(id="nodes-split"):
            yield self.launch_tree
            yield self.pane

    def on_mount(self) -> None:
        # held, not queried: the events keep coming while a modal is the active screen
        self.detail = self.query_one("#detail", Static)
        self.launch_tree.reported = self.store.reported_names

    def on_resize(self, event: events.Resize) -> None:
        """Below NARROW columns the tree goes above the pane, each half the height: beside
        it, a phone's 42 columns cut a node's name at about 15."""
        narrow = event.size.width < NARROW
        if narrow != self.has_class("-narrow"):
            self.set_class(narrow, "-narrow")
            self.query_one(NodesView).stack(narrow)

    # --- events ------------------------------------------------------------------------------

    def batch_shown(self, shown: Batch, news: bool) -> None:
        """A batch is in the tree and the pane (the view's `show_events`): a respawn's wait
        counts down once a second; `news` (not only readings): the detail line follows."""
        if shown.counting and self._countdown is None:
            self._countdown = self.set_interval(1.0, self._count_down)
        if news:
            self.update_detail()

    def show_lines(self, lines: list[Line]) -> None:
        """Lines of the app's own for the pane (the plan's warnings)."""
        if lines:
            self.pane.append(lines)
        self.pane.flush()

    def _count_down(self) -> None:
        if not self.events.count_down() and self._countdown is not None:
            self._countdown.stop()
            self._countdown = None
        self.update_detail()

    # --- the selection -----------------------------------------------------------------------

    def selected_process(self) -> str | None:
        node = self.launch_tree.cursor_node
        if node is None or node.data is None or node.data.kind != RowKind.PROCESS:
            return None
        return node.data.ref

    def show_all(self) -> None:
        """The all nodes row selected, its pane shown (`a`)."""
        tree = self.launch_tree
        tree.move_cursor(tree.root.children[0])
        self.pane.show_view(None)

    @on(Tree.NodeHighlighted, "#tree")
    def _highlighted(self, event: Tree.NodeHighlighted[RowData]) -> None:
        """The pane follows the selection (and the message goes on up: the keys that
        apply change with it)."""
        data = event.node.data
        self.update_detail()
        if data is not None and data.kind == RowKind.ALL:
            self.pane.show_view(None)
        elif data is not None and data.kind == RowKind.PROCESS:
            self.pane.show_view(data.ref)

    def update_detail(self) -> None:
        """The selected row in full above the tree and the pane: state, pid, exit code,
        failure reason or condition, whatever the tree's width cuts; its CPU and memory
        over the last minutes at the end, as two sparklines, when there is room."""
        node = self.launch_tree.cursor_node
        text = self.launch_tree.describe(node) if node is not None else ""
        process = self.selected_process()
        trend = list(self.trend_of(process) or ()) if process is not None else []
        # a column to spare: a line one cell too long would wrap
        room = self.detail.size.width - len(text) - 2 * (TREND_WIDTH + 5 + SCALE_WIDTH) - 1
        if len(trend) < 2 or room < 0:
            trend = []
        drawn = (text, process, tuple(trend))
        if drawn == self._detail_drawn:
            return  # the same picture is not sent to the terminal again
        self._detail_drawn = drawn
        line = Text(text, style=_detail_style(text))
        if trend:
            line.append(" " * room)
            cpu, memory = [c for c, _ in trend], [r for _, r in trend]
            # from zero to the max said after the bars: 10 % beside 12 % are alike
            for label, data, high in ((" cpu ", cpu, f"{max(cpu):.0f}%"),
                                      (" mem ", memory, short_bytes(max(memory)))):
                line.append(label, style="dim")
                line.append(spark(data, TREND_WIDTH))
                line.append(f" {high}".ljust(SCALE_WIDTH), style="dim")
        self.detail.update(line)

    # --- what a link did not send ------------------------------------------------------------

    @on(OutputPanel.GapShown)
    def _gap_shown(self, message: OutputPanel.GapShown) -> None:
        self.run_worker(self.gaps.read_gap(message.line, message.reading_up), group="gaps",
                        exit_on_error=False)

    @on(OutputPanel.StampsWanted)
    def _stamps_wanted(self, message: OutputPanel.StampsWanted) -> None:
        port = self.view.over_link()
        if port is None or self.gaps.stamps_known(port, message.shown):
            message.then()
            return
        self.run_worker(self._read_stamps(port, message), group="stamps",
                        exit_on_error=False)

    async def _read_stamps(self, port: LaunchPort, message: OutputPanel.StampsWanted) -> None:
        read = await self.gaps.read_stamps(port, message.shown)
        if read is None:
            message.then()  # the key still does its part
            return
        self.drain()  # the lines sent before the answer: in the queue before the stamps
        self.post_message(StampsRead(*read, message.then))

    def on_stamps_read(self, message: StampsRead) -> None:
        self.gaps.fill_stamps(message.first, message.end, message.stamps)
        message.then()


def _detail_style(text: str) -> str:
    if ": failed" in text or "refused" in text:
        return "bold red"
    return ""
