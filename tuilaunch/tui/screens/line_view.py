"""A bounded pane of output lines that stays cheap on a slow terminal.

Textual's Log stops repainting once it holds `max_lines` (its pruning keeps the scroll
position, so nothing looks changed) and repaints its scrollbar with every line. This view
draws only its visible rows, has no scrollbar (the pane's status line says where you are),
and repaints only when `flush` finds a change, at most `max_fps` times a second, so a
terminal over ssh receives what changed on screen and nothing else.

Scrolled back, the view holds still: its lines are frozen while the user reads, so a flood
neither trims what is on screen nor moves a search's matches. What arrives meanwhile waits
aside (the newest `max_lines` of it; the log files keep every line) and joins when the user
moves down past the last frozen line or follows again (`G`, `end`).
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable, Iterable

from rich.cells import cell_len
from rich.segment import Segment
from rich.text import Text
from textual import events
from textual.binding import Binding
from textual.strip import Strip
from textual.widget import Widget

from ..output_store import Gap, Line, replace_line

LEVEL_LETTER = "DIWEF"
# colour, and the letter says the same with 16 colours or NO_COLOR
LEVEL_STYLE = ("green", "", "yellow", "bold red", "bold white on red")
EVENT_STYLE = "bold cyan"
MATCH_STYLE = "reverse"
CURRENT_MATCH_STYLE = "bold black on yellow"


def display_text(line: Line, prefixed: bool, show_time: bool, raw: bool = False) -> Text:
    """The compact form: `[time ]id L message`; the id only when several processes share
    the pane, the ROS prefix replaced by one level letter (raw: the line as printed).

    An INFO line is one plain run of text: every style change costs bytes on the wire, on
    every repaint of a scrolling pane; levels above INFO colour their whole line."""
    parts = []
    if show_time:
        parts.append(time.strftime("%H:%M:%S", time.localtime(line.stamp))
                     + f".{int(line.stamp * 1000) % 1000:03d}")
    if prefixed:
        parts.append(line.process)
    if line.event:
        parts.append(f"-- {line.text}")
        style = EVENT_STYLE if line.level < 3 else LEVEL_STYLE[line.level]
    elif raw and line.colored is not None:  # the program's own colours, as printed
        parts.append("")
        text = Text(" ".join(parts), LEVEL_STYLE[line.level], no_wrap=True, end="")
        printed = Text.from_ansi(line.colored, no_wrap=True, end="")
        printed.expand_tabs(8)
        text.append_text(printed)
        return text
    elif raw:
        parts.append(line.text)
        style = LEVEL_STYLE[line.level]
    else:
        parts.append(f"{LEVEL_LETTER[line.level]} {line.message}")
        style = LEVEL_STYLE[line.level]
    return Text(" ".join(parts), style, no_wrap=True, end="")


class LineView(Widget, can_focus=True):
    DEFAULT_CSS = """
    LineView { height: 1fr; }
    """

    BINDINGS = [
        Binding("up", "scroll(-1)", "Up", show=False),
        Binding("down", "scroll(1)", "Down", show=False),
        Binding("pageup", "page(-1)", "Page up", show=False),
        Binding("pagedown", "page(1)", "Page down", show=False),
        Binding("home", "top", "Top", show=False),
        Binding("end", "follow", "Follow", show=False),
        Binding("left", "pan(-8)", "Left", show=False),
        Binding("right", "pan(8)", "Right", show=False),
    ]

    def __init__(self, max_lines: int = 5000, max_fps: float = 2.0, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.lines: deque[Line] = deque(maxlen=max_lines)
        self.total = 0  # lines ever appended: absolute indices stay valid while trimming
        self.newer: deque[Line] = deque(maxlen=max_lines)
        """Lines that came while scrolled back: kept aside so the view holds still."""
        self.skipped = 0
        """Lines that came while scrolled back and did not fit aside (all in the log files)."""
        self.following = True
        self.top = 0  # absolute index of the first visible line when not following
        self.x = 0
        self.wrap = False
        self.show_time = False
        self.raw = False
        self.prefixed = True
        self.search = ""
        self.current_match: int | None = None  # absolute index
        self.empty_text = ""
        """Said on the first row when there is no line (a filter nothing matches)."""
        self.partials: list[Line] = []
        """Unfinished lines (a prompt) shown below the last line while following."""
        self.max_fps = max_fps
        self._dirty = False
        self._painted_at = 0.0
        self._frame: list[Strip] | None = None
        self._frame_key: tuple[int, int] | None = None
        self.repaints = 0  # for tests and the benchmark: how often the pane was drawn
        # told when the user moves the view, so the owner's status line says so at once
        self.on_move: Callable[[], None] | None = None
        self.on_gap: Callable[[Line, bool], None] | None = None
        """Told of a line standing for lines not drawn (`Line.gap`) when the user scrolls
        back to it, with whether they were reading upwards; once per gap."""
        self.reading_up = False  # the last move went up: a gap read holds the lines below
        self._gaps_told: set[Gap] = set()

    # --- content ---------------------------------------------------------------------

    @property
    def first(self) -> int:
        return self.total - len(self.lines)

    def reset(self, lines: Iterable[Line]) -> None:
        self.lines.clear()
        self.lines.extend(lines)
        self.newer.clear()
        self.skipped = 0
        self.total = len(self.lines)
        self.following = True
        self.x = 0
        self.current_match = None
        self._invalidate(now=True)

    def set_partials(self, lines: list[Line]) -> None:
        """The unfinished lines to show below the last one; a prompt shows at once (a
        prompt comes alone, never in a flood)."""
        if lines == self.partials:
            return
        self.partials = lines
        if self.following:
            self._invalidate(now=True)

    def append(self, lines: list[Line]) -> None:
        if not lines:
            return
        if not self.following and (self.newer or len(self.lines) + len(lines)
                                   > max(self.size.height, 1)):
            # scrolled back over a full screen: what the user reads stays; the lines wait
            self.skipped += max(len(self.newer) + len(lines) - (self.newer.maxlen or 0), 0)
            self.newer.extend(lines)
            return
        self.lines.extend(lines)
        self.total += len(lines)
        self._dirty = True

    def replace(self, old: Line, new: list[Line]) -> None:
        """A line (a gap's marker) replaced by `new`, the view holding still: reading
        upwards, the lines below it keep their rows (the gap's lines show above them as
        the user goes on up); otherwise those above it do."""
        if replace_line(self.newer, old, new) is not None:
            return  # came while scrolled back: not on screen yet
        first = self.first
        position = replace_line(self.lines, old, new)
        if position is None:
            return  # trimmed meanwhile, or another view's
        at = first + position
        grown = len(new) - 1
        self.total += grown
        if self.current_match is not None:
            self.current_match = None if self.current_match == at else \
                self.current_match + (grown if self.current_match > at else 0)
        if not self.following and (self.top > at or (self.reading_up and self.top <= at)):
            self.top += grown
        self.top = max(self.top, self.first)
        self._invalidate(now=True)

    def thaw(self, count: int | None = None) -> None:
        """The oldest `count` lines that waited (all when None) join the view, after a line
        saying how many did not fit aside (the log files have them). A few at a time as
        the user moves down, so the lines on screen are not trimmed away."""
        if not self.newer and not self.skipped:
            return
        waiting: list[Line] = []
        if self.skipped:
            process = self.newer[0].process if self.newer else "launch"
            waiting.append(Line(process, f"{self.skipped} lines here are only in the "
                                         "log file", 0, time.time(), 0, True))
            self.skipped = 0
        take = len(self.newer) if count is None else min(count, len(self.newer))
        waiting += [self.newer.popleft() for _ in range(take)]
        self.lines.extend(waiting)
        self.total += len(waiting)
        self.top = max(self.top, self.first)
        self._dirty = True

    @property
    def unseen(self) -> int:
        """Lines below the last one on screen (exact, whatever was trimmed meanwhile)."""
        if self.following:
            return 0
        return max(self.total - 1 - self._bottom(), 0) + len(self.newer) + self.skipped

    def _bottom(self) -> int:
        height = max(self.size.height, 1)
        rows, index = 0, max(self.top, self.first)
        while index < self.total and rows < height:
            rows += self._row_count(index)
            index += 1
        return index - 1

    # --- repainting ------------------------------------------------------------------

    def flush(self, now: float | None = None) -> bool:
        """Repaints if something visible changed and the last repaint is old enough."""
        now = time.monotonic() if now is None else now
        if not self._dirty or now - self._painted_at < 1 / self.max_fps:
            return False
        self._invalidate(now)
        return True

    def _invalidate(self, now: float | bool = False) -> None:
        self._dirty = False
        self._frame = None
        self._painted_at = time.monotonic() if now is True or now is False else float(now)
        self.repaints += 1
        self.refresh()

    def set_options(self, *, wrap: bool | None = None, show_time: bool | None = None,
                    raw: bool | None = None, prefixed: bool | None = None,
                    search: str | None = None) -> None:
        if wrap is not None:
            self.wrap = wrap
            self.x = 0
        if show_time is not None:
            self.show_time = show_time
        if raw is not None:
            self.raw = raw
        if prefixed is not None:
            self.prefixed = prefixed
        if search is not None:
            self.search = search
            self.current_match = None
        self._invalidate(now=True)

    def on_resize(self, event: events.Resize) -> None:
        self._frame = None  # following stays as it was: the tail stays in view

    def _text(self, index: int) -> Text:
        line = self.lines[index - self.first]
        text = display_text(line, self.prefixed, self.show_time, self.raw)
        if self.search:
            text.highlight_words([self.search], MATCH_STYLE, case_sensitive=False)
            if index == self.current_match:
                text.stylize(CURRENT_MATCH_STYLE)
        return text

    def _wrapped(self, index: int) -> list[Text]:
        width = max(self.size.width, 1)
        text = self._text(index)
        if text.cell_len <= width:
            return [text]
        return list(text.wrap(self.app.console, width, no_wrap=False))

    def _rows(self, index: int) -> list[Text]:
        """A line's rows: tuilaunch's own lines (a death and its reason) always wrap, so
        they are read whole at 80 columns; the others only with `z`."""
        if self.wrap or self.lines[index - self.first].event:
            return self._wrapped(index)
        return [self._text(index)]

    def _row_count(self, index: int) -> int:
        if self.wrap or self.lines[index - self.first].event:
            return len(self._wrapped(index))
        return 1

    def _compose_frame(self) -> list[Strip]:
        width, height = self.size.width, self.size.height
        rows: list[Text] = []
        if not self.lines and self.empty_text:
            rows.append(Text(self.empty_text, "italic", no_wrap=True, end=""))
        elif self.following:
            rows = [display_text(line, self.prefixed, self.show_time, self.raw)
                    for line in self.partials][-height:]
            index = self.total - 1
            while index >= self.first and len(rows) < height:
                rows[0:0] = self._rows(index)
                index -= 1
            rows = rows[-height:] if rows else rows
            self.top = index + 1 if self.total else 0
        else:
            self.top = max(min(self.top, self.total - 1), self.first)
            index = self.top
            while index < self.total and len(rows) < height:
                rows += self._rows(index)
                index += 1
            rows = rows[:height]
            self._tell_gaps(self.top, index)
        base = self.rich_style
        strips = []
        for text in rows:
            segments = list(text.render(self.app.console))
            strip = Strip(segments, cell_len(text.plain))
            if not self.wrap and self.x:
                strip = strip.crop(self.x, self.x + width)
            # one run per style: the padding joins the text's run, fewer escapes to send
            strips.append(strip.extend_cell_length(width, base).crop(0, width)
                          .apply_style(base).simplify())
        blank = Strip([Segment(" " * width, base)], width)
        strips += [blank] * (height - len(strips))
        return strips

    def _tell_gaps(self, top: int, end: int) -> None:
        """Scrolled back, the gaps on screen are read (once each). Told after this frame,
        from this widget's own turn: a message made while the screen composes would come
        from the screen, and stop there instead of reaching the app."""
        if self.on_gap is None:
            return
        for index in range(top, end):
            line = self.lines[index - self.first]
            if line.gap is not None and line.gap not in self._gaps_told:
                self._gaps_told.add(line.gap)
                self.call_later(self.on_gap, line, self.reading_up)

    def gap_not_read(self, line: Line) -> None:
        """A gap whose reading failed: told again when next on screen."""
        self._gaps_told.discard(line.gap)

    def render_line(self, y: int) -> Strip:
        key = (self.size.width, self.size.height)
        if self._frame is None or self._frame_key != key:
            self._frame = self._compose_frame()
            self._frame_key = key
        if y < len(self._frame):
            return self._frame[y]
        return Strip.blank(self.size.width, self.rich_style)

    # --- moving ----------------------------------------------------------------------

    def _visible_top(self) -> int:
        if self._frame is None:
            self._compose_frame()
        return self.top

    def scroll_to_line(self, index: int) -> None:
        """Shows line `index` (absolute) near the middle, and holds it there: a flood does
        not carry it away (`G` follows again)."""
        height = max(self.size.height, 1)
        self._visible_top()
        self.following = False
        self.reading_up = False
        self.top = max(min(index - height // 2, self.total - height), self.first)
        self._invalidate(now=True)

    def action_scroll(self, step: int) -> None:
        top = self._visible_top()
        self.reading_up = step < 0
        if self.following and step > 0:
            return  # already at the newest line: stay there, following
        if step > 0 and self._bottom() + step >= self.total:
            self.thaw(step)  # moving past the last frozen line: what waited comes next
        self.top = max(min(top + step, self.total - 1), self.first)
        # at the newest line (scrolled back down, or nothing to scroll): follow
        self.following = self._bottom() >= self.total - 1 and not self.newer
        self._moved()

    def action_page(self, direction: int) -> None:
        self.action_scroll(direction * max(self.size.height - 1, 1))

    def action_top(self) -> None:
        self.reading_up = False  # from the oldest line down
        self.following = False
        self.top = self.first
        self._moved()

    def action_follow(self) -> None:
        self.thaw()
        self.following = True
        self._moved()

    def _moved(self) -> None:
        self._invalidate(now=True)
        if self.on_move is not None:
            self.on_move()

    def action_pan(self, step: int) -> None:
        if self.wrap:
            return
        self.x = max(self.x + step, 0)
        self._invalidate(now=True)

    def on_mouse_scroll_up(self, event: events.MouseScrollUp) -> None:
        event.stop()
        self.action_scroll(-3)

    def on_mouse_scroll_down(self, event: events.MouseScrollDown) -> None:
        event.stop()
        self.action_scroll(3)

    # --- reading ---------------------------------------------------------------------

    def matches(self) -> list[int]:
        if not self.search:
            return []
        term = self.search.lower()
        first = self.first
        return [first + i for i, line in enumerate(self.lines) if term in line.text.lower()]

    def visible_text(self) -> list[str]:
        """The rows on screen as plain text (what a user reads; tests check it)."""
        key = (self.size.width, self.size.height)
        if self._frame is None or self._frame_key != key:
            self._frame = self._compose_frame()
            self._frame_key = key
        return [strip.text.rstrip() for strip in self._frame]
