"""The output pane: one process's lines or all of them, with search, filters and follow."""

from __future__ import annotations

import re
import time
from pathlib import Path

from rich.highlighter import Highlighter
from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import Input, Log, Static

from ..output_store import LEVELS, Line, OutputStore, View

_LEVEL_STYLES = {"DEBUG": "green", "INFO": "", "WARN": "yellow", "WARNING": "yellow",
                 "ERROR": "bold red", "FATAL": "bold white on red"}
_LEVEL_RE = re.compile(r"\[(DEBUG|INFO|WARN|WARNING|ERROR|FATAL)\]")
_PREFIX_RE = re.compile(r"^\[[\w.-]+-\d+\]")


class OutputHighlighter(Highlighter):
    """ROS levels in colour, the `[process-id]` prefix, and search matches reversed."""

    def __init__(self) -> None:
        self.search = ""

    def highlight(self, text: Text) -> None:
        plain = text.plain
        prefix = _PREFIX_RE.match(plain)
        if prefix:
            text.stylize("cyan", 0, prefix.end())
        level = _LEVEL_RE.search(plain)
        if level is not None and _LEVEL_STYLES[level.group(1)]:
            # errors colour their whole line, so they stand out in a scrolling pane
            whole = level.group(1) in ("ERROR", "FATAL")
            text.stylize(_LEVEL_STYLES[level.group(1)], level.start(),
                         len(plain) if whole else level.end())
        if self.search:
            text.highlight_words([self.search], style="reverse", case_sensitive=False)


class OutputLog(Log):
    """A Log whose highlighting can change (search term) without rewriting its lines."""

    def __init__(self, **kwargs: object) -> None:
        super().__init__(highlight=True, **kwargs)  # type: ignore[arg-type]
        self.output_highlighter = OutputHighlighter()
        self.highlighter = self.output_highlighter

    def set_search(self, term: str) -> None:
        self.output_highlighter.search = term
        self._render_line_cache.clear()
        self.refresh()


class OutputPanel(Vertical):
    """Forwards nothing to the engine: the app feeds it lines from the OutputStore."""

    DEFAULT_CSS = """
    OutputPanel { height: 1fr; }
    OutputPanel #output-status { height: 1; background: $boost; color: $text-muted; }
    OutputPanel OutputLog { height: 1fr; }
    OutputPanel Input { display: none; height: 3; }
    OutputPanel Input.shown { display: block; }
    """

    def __init__(self, store: OutputStore, save_dir: Path, max_lines: int = 5000,
                 **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.store = store
        self.save_dir = save_dir
        self.view = View()
        self.search = ""
        self.match_index = -1
        self.unseen = 0
        self.max_lines = max_lines
        # held rather than queried: the app feeds the pane on a timer, even mid-teardown
        self._status = Static(id="output-status")
        self._log = OutputLog(max_lines=max_lines, id="output-log")

    def compose(self) -> ComposeResult:
        yield self._status
        yield self._log
        yield Input(placeholder="search (enter: find, esc: clear)", id="search-input")
        yield Input(placeholder="show only lines containing... (empty: all)",
                    id="filter-input")

    def on_mount(self) -> None:
        self.show_view(None)

    @property
    def log_widget(self) -> OutputLog:
        return self._log

    # --- feeding -----------------------------------------------------------------------

    def show_view(self, process: str | None) -> None:
        self.view.process = process
        self._rebuild()

    def _rebuild(self) -> None:
        log = self.log_widget
        log.clear()
        log.write_lines(self.store.text(self.view), scroll_end=True)
        self.unseen = 0
        self.update_status()

    def append(self, lines: list[Line]) -> None:
        shown = [line.formatted(self.view.process is None) for line in lines
                 if self.view.accepts(line)]
        if not shown:
            return
        log = self.log_widget
        following = log.is_vertical_scroll_end
        log.write_lines(shown)
        if not following:
            self.unseen += len(shown)

    def update_status(self) -> None:
        log = self.log_widget
        if log.is_vertical_scroll_end:
            self.unseen = 0
        parts = [f"output: {self.view.process or 'all nodes'}",
                 f"level {LEVELS[self.view.min_level]}+"]
        if self.view.text:
            parts.append(f"filter '{self.view.text}'")
        if self.search:
            matches = self._matches()
            where = f"{self.match_index + 1}/{len(matches)}" if matches else "no match"
            parts.append(f"search '{self.search}' {where}")
        if self.unseen:
            parts.append(f"{self.unseen} new lines (G: follow)")
        self._status.update(Text("  ".join(parts)))

    # --- search and filters --------------------------------------------------------------

    def _matches(self) -> list[int]:
        term = self.search.lower()
        return [i for i, line in enumerate(self.log_widget.lines) if term in line.lower()]

    def action_search(self) -> None:
        field = self.query_one("#search-input", Input)
        field.add_class("shown")
        field.value = self.search
        field.focus()

    def action_filter(self) -> None:
        field = self.query_one("#filter-input", Input)
        field.add_class("shown")
        field.value = self.view.text
        field.focus()

    @on(Input.Submitted, "#search-input")
    def _search_submitted(self, event: Input.Submitted) -> None:
        self.set_search(event.value)
        event.input.remove_class("shown")
        self.log_widget.focus()

    @on(Input.Submitted, "#filter-input")
    def _filter_submitted(self, event: Input.Submitted) -> None:
        self.view.text = event.value
        event.input.remove_class("shown")
        self._rebuild()
        self.log_widget.focus()

    def set_search(self, term: str) -> None:
        self.search = term
        self.log_widget.set_search(term)
        self.match_index = -1
        if term:
            self.action_next_match()
        self.update_status()

    def action_clear_search(self) -> None:
        for field in self.query(Input):
            field.remove_class("shown")
        self.set_search("")
        self.log_widget.focus()

    def _jump(self, step: int) -> None:
        matches = self._matches()
        if not matches:
            self.match_index = -1
        else:
            self.match_index = (self.match_index + step) % len(matches)
            line = matches[self.match_index]
            self.log_widget.scroll_to(y=max(line - self.log_widget.size.height // 2, 0),
                                      animate=False)
        self.update_status()

    def action_next_match(self) -> None:
        self._jump(1)

    def action_previous_match(self) -> None:
        self._jump(-1)

    def action_cycle_level(self) -> None:
        self.view.min_level = (self.view.min_level + 1) % len(LEVELS)
        self._rebuild()

    def action_follow(self) -> None:
        self.log_widget.scroll_end(animate=False)
        self.unseen = 0
        self.update_status()

    # --- export --------------------------------------------------------------------------

    def pane_text(self) -> str:
        return "\n".join(self.log_widget.lines) + "\n"

    def action_save(self) -> None:
        self.save_dir.mkdir(parents=True, exist_ok=True)
        name = (self.view.process or "all") + time.strftime("-pane-%H%M%S.txt")
        path = self.save_dir / name
        path.write_text(self.pane_text())
        self.notify(f"pane saved to {path}")

    def action_copy(self) -> None:
        self.app.copy_to_clipboard(self.pane_text())
        self.notify(f"copied {len(self.log_widget.lines)} lines (OSC 52 clipboard)")


class NodesView(Horizontal):
    """The tree beside the output pane: the pane's keys work wherever the focus is."""

    BINDINGS = [
        Binding("slash", "pane('search')", "Search", tooltip="Highlight a text; n / N jump"),
        Binding("n", "pane('next_match')", "Next", show=False),
        Binding("N", "pane('previous_match')", "Prev", show=False),
        Binding("l", "pane('cycle_level')", "Level",
                tooltip="Show only lines from this ROS level up"),
        Binding("backslash", "pane('filter')", "Filter",
                tooltip="Show only lines containing a text"),
        Binding("G", "pane('follow')", "Follow", show=False, tooltip="Back to the newest line"),
        Binding("w", "pane('save')", "Save", show=False, tooltip="Write this pane to a file"),
        Binding("y", "pane('copy')", "Copy", show=False, tooltip="Copy this pane to the clipboard"),
        Binding("escape", "pane('clear_search')", "Clear", show=False),
    ]

    def action_pane(self, name: str) -> None:
        getattr(self.query_one(OutputPanel), f"action_{name}")()
