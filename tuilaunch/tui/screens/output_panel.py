"""The output pane: one process's lines or all of them, with search, filters and follow."""

from __future__ import annotations

import dataclasses
import shlex
import time
from collections.abc import Awaitable, Callable
from pathlib import Path

from rich.cells import cell_len
from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import Static

from ..output_store import LEVELS, Line, OutputStore, View
from .fields import Field
from .line_view import LineView
from .tree_panel import ascii_terminal


def plural(count: int, word: str) -> str:
    return f"{count} {word}" if count == 1 else f"{count} {word}s"


FOCUS_MARK = "▶"
"""Starts the pane's status line while the pane has the keys."""


@dataclasses.dataclass
class GapsRead:
    """The lines of a pane's gaps read back for `w` and `y` (by the marker's identity), and
    those left unread (how many, why)."""

    lines: dict[int, list[Line]] = dataclasses.field(default_factory=dict)
    unread: int = 0
    why: str = ""


GapSource = Callable[[list[Line]], Awaitable[GapsRead]]
"""Reads every line of these gaps through the session (nodes/gaps.py's GapReader)."""

GAPS_SAID = 2000
"""Lines to read back for a save above which the pane says it reads them (a moment)."""


class OutputPanel(Vertical):
    """Forwards nothing to the engine: the app feeds it lines from the OutputStore, and
    reads a flood's lines not drawn when the pane asks (GapShown)."""

    class GapShown(Message):
        """The user scrolled back to a line standing for lines not drawn: read them."""

        def __init__(self, line: Line, reading_up: bool) -> None:
            super().__init__()
            self.line = line
            self.reading_up = reading_up

    class StampsWanted(Message):
        """The pane is about to show or export its lines with their ROS stamps (the time
        column, the raw format, a save): lines that came over a link without them get
        them first, then `then` runs. `shown`: whether the pane shows stamps from now on,
        so the link sends them with the lines (or leaves them out again)."""

        def __init__(self, shown: bool, then: Callable[[], None]) -> None:
            super().__init__()
            self.shown = shown
            self.then = then

    DEFAULT_CSS = """
    OutputPanel { height: 1fr; }
    OutputPanel #output-status { height: 1; background: $boost; color: $text-muted; }
    OutputPanel Field { display: none; }
    OutputPanel Field.shown { display: block; }
    """

    def __init__(self, store: OutputStore, save_dir: Path, max_lines: int = 5000,
                 max_fps: float = 2.0, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.store = store
        self.save_dir = save_dir
        self.view = View()
        self.search = ""
        self.match_index = -1
        self.max_lines = max_lines
        self._time = self._raw = False  # as the keys asked: shown once the stamps are here
        # held rather than queried: the app feeds the pane on a timer, even mid-teardown
        self._status = Static(id="output-status")
        self._status_text = ""
        self._lines = LineView(max_lines=max_lines, max_fps=max_fps, id="output-lines")
        self._lines.on_move = self.update_status
        self._lines.on_gap = self._gap_shown
        self._partials_seen = -1  # the store's partials_changed when last shown
        self.read_gaps: GapSource | None = None
        """What reads the gaps' lines before a save or copy (set by the GapReader that
        fills this pane's gaps; None: no session to read them from)."""

    def compose(self) -> ComposeResult:
        yield self._status
        yield self._lines
        yield Field(placeholder="search (enter: find, esc: cancel)", id="search-input",
                    leave_on_enter=True)
        yield Field(placeholder="show only lines containing... (empty: all)",
                    id="filter-input", leave_on_enter=True)

    def on_mount(self) -> None:
        self.show_view(None)

    @property
    def line_view(self) -> LineView:
        return self._lines

    @property
    def unseen(self) -> int:
        return self._lines.unseen

    # --- feeding -----------------------------------------------------------------------

    def show_view(self, process: str | None) -> None:
        """Another node (or all): its newest lines, followed."""
        self.view.process = process
        self._lines.prefixed = process is None
        self._rebuild()

    def _rebuild(self) -> None:
        self._lines.empty_text = self._nothing_shown()
        self._lines.reset(self.store.lines(self.view))
        self._partials_seen = -1
        self._show_partials()
        if self.search:
            self._lines.search = self.search
        self.match_index = -1
        self.update_status()

    def _nothing_shown(self) -> str:
        """What an empty pane says: which filter hides every line, and the key that
        undoes it."""
        level = self.view.min_level
        if self.view.text:
            which = f"no {LEVELS[level]}+ line" if level else "no line"
            return f"{which} matches '{self.view.text}' (esc: show all)"
        if level:
            return f"no line at {LEVELS[level]} or above (l: next level)"
        return ""

    def append(self, lines: list[Line]) -> None:
        self._lines.append([line for line in lines if self.view.accepts(line)])

    def _gap_shown(self, line: Line, reading_up: bool) -> None:
        self.post_message(self.GapShown(line, reading_up))

    def fill_gap(self, marker: Line, lines: list[Line]) -> None:
        """A gap's marker replaced by its lines read from the log file (and a marker for
        the rest, when it held more than one read brings)."""
        self._lines.replace(marker, [line for line in lines if self.view.accepts(line)])
        self.update_status()

    def gap_not_read(self, marker: Line) -> None:
        self._lines.gap_not_read(marker)

    def _show_partials(self) -> None:
        if self._partials_seen != self.store.partials_changed:
            self._partials_seen = self.store.partials_changed
            self._lines.set_partials(self.store.partial_lines(self.view))

    def flush(self) -> None:
        """Called on the app's tick: repaints what changed, at the pane's rate."""
        self._show_partials()
        self._lines.flush()
        self.update_status()

    def update_status(self) -> None:
        lines = self._lines
        # each part in full and short: the short forms when the full line does not fit the
        # pane's width (an 80-column terminal leaves the pane about 50)
        parts = [(self.view.process or "all nodes",) * 2,
                 (f"{LEVELS[self.view.min_level]}+", f"{LEVELS[self.view.min_level][0]}+")]
        if self.view.text:
            parts.append((f"only '{self.view.text}'", f"\\{self.view.text}"))
        if self.search:
            matches = lines.matches()
            where = f"{self.match_index + 1}/{len(matches)}" if matches else \
                "no line matches"
            parts.append((f"/{self.search} {where}",) * 2)
        if lines.wrap:
            parts.append(("wrap", "z"))
        if not lines.following:
            unseen = lines.unseen
            parts.append((f"{plural(unseen, 'new line')} (G: follow)", f"{unseen} new (G)")
                         if unseen else ("paused (G: follow)", "paused (G)"))
        hidden = self._not_drawn()
        if hidden:
            parts.append((f"{hidden} not drawn (in log)", f"{hidden} in log"))
        # the pane has the keys (arrows scroll it): said in words at the line's start, as a
        # colour alone shows on no 8-colour or NO_COLOR terminal
        mark = f"{'>' if ascii_terminal() else FOCUS_MARK} " if lines.has_focus else ""
        text = mark + "  ".join(full for full, _ in parts)
        width = self._status.size.width
        if width and cell_len(text) > width:
            text = mark + " ".join(short for _, short in parts)
        if text != self._status_text:  # an unchanged line is not sent to the terminal again
            self._status_text = text
            # still too long (a long node name): cut where it shows, with an ellipsis
            self._status.update(Text(text, no_wrap=True, overflow="ellipsis"))

    def _not_drawn(self) -> int:
        """Lines of this pane's view a flood kept off the screen (in the log files)."""
        dropped = self.store.dropped
        return dropped.total if self.view.process is None else \
            dropped.per_process.get(self.view.process, 0)

    def on_descendant_focus(self) -> None:
        self.update_status()

    def on_descendant_blur(self) -> None:
        self.update_status()

    def on_resize(self) -> None:
        self._status_text = ""  # measured again against the new width
        self.call_after_refresh(self.update_status)

    # --- search and filters --------------------------------------------------------------

    def action_search(self) -> None:
        field = self.query_one("#search-input", Field)
        field.add_class("shown")
        field.value = self.search
        field.focus()

    def action_filter(self) -> None:
        field = self.query_one("#filter-input", Field)
        field.add_class("shown")
        field.value = self.view.text
        field.focus()

    @on(Field.Submitted, "#search-input")
    def _search_submitted(self, event: Field.Submitted) -> None:
        event.input.remove_class("shown")
        self.set_search(event.value)

    @on(Field.Submitted, "#filter-input")
    def _filter_submitted(self, event: Field.Submitted) -> None:
        self.view.text = event.value
        event.input.remove_class("shown")
        self._rebuild()

    def set_search(self, term: str) -> None:
        self.search = term
        self._lines.set_options(search=term)
        self.match_index = -1
        if term:
            self.action_next_match()
            if not self._lines.matches():
                self.notify(self._not_found(term), severity="warning")
        self.update_status()

    def _not_found(self, term: str) -> str:
        """What a search that found nothing says: when the pane no longer holds every line
        (trimmed to its scrollback, or not drawn under a flood), where the others are."""
        lines = self._lines
        full = len(lines.lines) >= (lines.lines.maxlen or 0) or lines.first > 0
        if not (full or self._not_drawn() or lines.skipped):
            return f"no line matches '{term}'"
        command = self._logs_command()
        where = f"; every line is in the log files: {command} | grep -F -- " \
                f"{shlex.quote(term)}" if command else "; every line is in the log files"
        return f"no line matches '{term}' in the {len(lines.lines)} lines this pane keeps{where}"

    def _logs_command(self) -> str | None:
        """`tuilaunch logs [HOST:]NAME [PROCESS]`: every line of this pane's view."""
        session = getattr(self.app, "session_name", None)
        if not session:
            return None
        host = getattr(self.app, "session_host", None)
        words = ["tuilaunch", "logs", f"{host}:{session}" if host else str(session)]
        if self.view.process is not None:
            words.append(self.view.process)
        return " ".join(shlex.quote(w) for w in words)

    def action_clear_search(self) -> None:
        """Escape: closes an open field, else clears the search and the text filter."""
        open_fields = [f for f in self.query(Field) if f.has_class("shown")]
        for field in open_fields:
            field.remove_class("shown")
        if not open_fields:
            if self.search:
                self.set_search("")
            if self.view.text:
                self.view.text = ""
                self._rebuild()
        self.update_status()

    def _jump(self, step: int) -> None:
        matches = self._lines.matches()
        if not matches:
            self.match_index = -1
        else:
            self.match_index = (self.match_index + step) % len(matches)
            self._lines.current_match = matches[self.match_index]
            self._lines.scroll_to_line(matches[self.match_index])
        self.update_status()

    def action_next_match(self) -> None:
        self._jump(1)

    def action_previous_match(self) -> None:
        self._jump(-1)

    def action_cycle_level(self) -> None:
        self.view.min_level = (self.view.min_level + 1) % len(LEVELS)
        self._rebuild()

    def action_follow(self) -> None:
        self._lines.action_follow()
        self.update_status()

    def action_wrap(self) -> None:
        self._lines.set_options(wrap=not self._lines.wrap)
        self.update_status()

    def action_time(self) -> None:
        self._time = not self._time
        self._with_stamps(self._show_options)

    def action_raw(self) -> None:
        self._raw = not self._raw
        self._with_stamps(self._show_options)

    def _show_options(self) -> None:
        # as asked by the last key (T twice quickly: off again), whenever the stamps come
        self._lines.set_options(show_time=self._time, raw=self._raw)

    def _with_stamps(self, then: Callable[[], None]) -> None:
        self.post_message(self.StampsWanted(self._time or self._raw, then))

    def stamps_read(self) -> None:
        """Lines got their ROS stamps: drawn again if shown."""
        self._lines.set_options()

    # --- export --------------------------------------------------------------------------

    def pane_lines(self, read: GapsRead | None = None) -> list[str]:
        """The pane's lines in full, as the processes printed them; a gap's lines in place
        of its marker where `read` has them."""
        prefixed = self.view.process is None
        got = read.lines if read is not None else {}
        lines: list[str] = []
        for line in (*self._lines.lines, *self._lines.newer):
            kept = got.get(id(line)) if line.gap is not None else None
            lines += [line.formatted(prefixed)] if kept is None else \
                [each.formatted(prefixed) for each in kept if self.view.accepts(each)]
        return lines

    def pane_text(self, read: GapsRead | None = None) -> str:
        return "\n".join(self.pane_lines(read)) + "\n"

    def gaps(self) -> list[Line]:
        """The markers of lines not drawn that the pane holds, oldest first."""
        return [line for line in (*self._lines.lines, *self._lines.newer)
                if line.gap is not None]

    def action_save(self) -> None:
        self._export(self._save)

    def action_copy(self) -> None:
        self._export(self._copy)

    def _export(self, then: Callable[[GapsRead], None]) -> None:
        """`w`, `y`: the pane with every line it stands for. Its ROS stamps first, then
        the lines a flood or a reconnection left in the log file (a marker in the pane)
        are read through the session, so the file holds them, not the marker."""
        def with_gaps() -> None:
            markers, reader = self.gaps(), self.read_gaps
            if not markers or reader is None:
                then(GapsRead())
                return
            self.run_worker(self._read_then(reader, markers, then), group="export",
                            exit_on_error=False)

        self._with_stamps(with_gaps)

    async def _read_then(self, reader: GapSource, markers: list[Line],
                         then: Callable[[GapsRead], None]) -> None:
        count = sum(line.gap.count for line in markers if line.gap is not None)
        if count > GAPS_SAID:  # a moment over a slow link: said, so w seems not ignored
            self.notify(f"reading {count} lines not drawn from the log files...")
        then(await reader(markers))

    def _not_read(self, read: GapsRead) -> None:
        """Lines a save or copy could not read back: said, with where they are."""
        if not read.unread:
            return
        command = self._logs_command()
        where = f"; {command} has them" if command else ""
        self.notify(f"{plural(read.unread, 'line')} not drawn could not be read "
                    f"({read.why}): a line stands for them{where}", severity="warning",
                    timeout=15)

    def _save(self, read: GapsRead) -> None:
        self.save_dir.mkdir(parents=True, exist_ok=True)
        name = (self.view.process or "all") + time.strftime("-pane-%H%M%S.txt")
        path = self.save_dir / name
        path.write_text(self.pane_text(read))
        if self.app.is_web:  # in a browser (tuilaunch serve): the file is its download too
            self.app.deliver_text(path, save_filename=name)
            self.notify(f"pane saved to {path}; the browser downloads it as {name}")
        else:
            self.notify(f"pane saved to {path}")
        self._not_read(read)

    def _copy(self, read: GapsRead) -> None:
        lines = self.pane_lines(read)
        self.app.copy_to_clipboard("\n".join(lines) + "\n")
        self.notify(f"copied {len(lines)} lines (OSC 52 clipboard)")
        self._not_read(read)


PANE_BINDINGS: list[BindingType] = [
    Binding("slash", "pane('search')", "Search", tooltip="Highlight a text; n / N jump"),
    Binding("n", "pane('next_match')", "Next", show=False),
    Binding("N", "pane('previous_match')", "Prev", show=False),
    Binding("l", "pane('cycle_level')", "Level",
            tooltip="Show only lines from this ROS level up"),
    Binding("backslash", "pane('filter')", "Filter",
            tooltip="Show only lines containing a text"),
    Binding("G", "pane('follow')", "Follow", show=False, tooltip="Back to the newest line"),
    Binding("z", "pane('wrap')", "Wrap", show=False, tooltip="Wrap long lines"),
    Binding("T", "pane('time')", "Time", show=False, tooltip="Show timestamps"),
    Binding("f", "pane('raw')", "Format", show=False,
            tooltip="Lines as printed, or compact"),
    Binding("w", "pane('save')", "Save", show=False, tooltip="Write this pane to a file"),
    Binding("y", "pane('copy')", "Copy", show=False, tooltip="Copy this pane to the clipboard"),
    Binding("escape", "pane('clear_search')", "Clear", show=False),
    Binding("less_than_sign", "resize(-4)", "Narrower tree", show=False),
    Binding("greater_than_sign", "resize(4)", "Wider tree", show=False),
]
"""The output pane's keys, wherever the focus is in the Nodes view: NodesView binds them, the
fleet view too (each on the selected session's pane)."""


class NodesView(Horizontal):
    """The tree beside the output pane: the pane's keys work wherever the focus is."""

    BINDINGS = PANE_BINDINGS

    tree_width: int | None = None  # None: adapts to the terminal's width
    stacked = False
    """The tree above the pane (NodesTab's narrow layout): its width is then the CSS's."""

    def action_pane(self, name: str) -> None:
        getattr(self.query_one(OutputPanel), f"action_{name}")()

    def stack(self, stacked: bool) -> None:
        """The tree above the pane (its width left to the CSS) or beside it."""
        self.stacked = stacked
        self._apply_width()

    def on_resize(self) -> None:
        self._apply_width()

    def adaptive_width(self) -> int:
        """About a third of the width, 22 to 44 columns: the pane keeps the rest."""
        return max(22, min(44, self.size.width * 35 // 100))

    def _apply_width(self) -> None:
        from .tree_panel import LaunchTree

        tree = self.query_one(LaunchTree)
        if self.stacked:
            tree.styles.width = None
            return
        width = self.tree_width if self.tree_width is not None else self.adaptive_width()
        width = max(12, min(width, max(self.size.width - 20, 12)))
        if tree.styles.width is None or tree.styles.width.value != width:
            tree.styles.width = width

    def action_resize(self, step: int) -> None:
        from .tree_panel import LaunchTree

        current = self.query_one(LaunchTree).outer_size.width or self.adaptive_width()
        self.tree_width = current + step
        self._apply_width()
