"""The Topics tab: every topic of the graph with its publishers and subscribers, live rates
for the rows on screen, the QoS pairs that cannot talk, and an echo of the selected topic.

Everything comes from the session server (`topics`, `watch_rates`, `echo`), which measures
where the nodes run; the panel asks for rates of the rows it shows only, and redraws only
the cells whose text changed.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import DataTable, Input, Static

from ...engine.run.vocabulary.requests import EchoStart, EchoStop, Topics, WatchRates
from . import units
from .fields import Field
from .graph_listing import discovering
from .tree_panel import ascii_terminal
from .units import bytes_text, rate_text

Request = Callable[..., Awaitable[Any]]
"""`await request(request)`: a session request's result, or an exception saying why."""

REFRESH_TICKS = 3
"""The topic list is asked for again every this many ticks (one a second) while shown."""
ECHO_KEEP = 5
"""Echoed messages kept on screen: the newest, as many as fit."""
ECHO_PER_S = 2.0
"""Echoed messages sent per second at most: readable, and cheap over ssh."""
RATE_HISTORY = 300
"""Rates kept per watched topic, one a second (the server sends the minutes before)."""

# (key, title, fixed width or None for the content's)
COLUMNS = (("topic", "topic", None), ("pubs", "pub", 3), ("subs", "sub", 3),
           ("rate", "rate", 9), ("bw", "bandwidth", 11), ("qos", "qos", 3),
           ("type", "type", None))


class QuietTable(DataTable[Any]):
    """A DataTable whose `set_cell` repaints that one cell, not the whole table
    (DataTable.update_cell refreshes every visible row: a full table per tick over ssh)."""

    quiet = False

    def set_cell(self, row: str, column: str, value: Any) -> None:
        self.quiet = True
        try:
            self.update_cell(row, column, value)
        finally:
            self.quiet = False
        self.refresh_coordinate(self.get_cell_coordinate(row, column))

    def refresh(self, *regions: Any, **kwargs: Any) -> Any:
        if self.quiet and not regions and not kwargs:
            return self  # update_cell's whole-table refresh; set_cell refreshes the cell
        return super().refresh(*regions, **kwargs)


def row_values(name: str, entry: Mapping[str, Any], rate: Mapping[str, Any],
               problem_mark: str) -> dict[str, Any]:
    """A topic's row, by column key: its `topics` entry and its last rates."""
    return {
        "topic": name,
        "pubs": str(len(entry.get("publishers") or [])),
        "subs": str(len(entry.get("subscribers") or [])),
        "rate": rate_text(rate.get("rate_hz")) if rate else "",
        "bw": bytes_text(rate.get("bytes_per_s"), "/s") if rate else "",
        "qos": Text(problem_mark, "bold red") if entry.get("qos_problems") else "",
        "type": ", ".join(str(t) for t in entry.get("types") or []),
    }


def endpoint_line(endpoint: Mapping[str, Any]) -> str:
    """`/talker  [talker-1]  reliable, volatile, keep_last 10`."""
    process = endpoint.get("process")
    if process:
        where = f"[{process}]"
    elif endpoint.get("in_launch"):
        where = "(this launch)"
    else:
        where = "(not in this launch)"
    qos = endpoint.get("qos") or {}
    policies = [str(qos[k]) for k in ("reliability", "durability") if qos.get(k)]
    history = qos.get("history")
    if history and history != "unknown":
        depth = qos.get("depth")
        policies.append(f"{history} {depth}" if depth is not None else str(history))
    return f"  {endpoint.get('node', '?')}  {where}  {', '.join(policies)}"


class TopicRates:
    """The rates the server measures for the panel: of the rows on screen only, each with
    its last minutes (the selected one's is the sparkline) or why it has none."""

    def __init__(self) -> None:
        self.watched: list[str] = []
        """The topics the server measures for us (the rows on screen)."""
        self.rates: dict[str, dict[str, Any]] = {}
        self.history: dict[str, deque[float]] = {}
        """A rate a second of each watched topic, oldest first."""
        self.unmeasured: dict[str, str] = {}
        """Watched topics the server cannot measure, and why."""

    def watch(self, topics: list[str]) -> list[str]:
        """The topics watched from now on; the ones no longer watched, returned, lose their
        figure: an old one would pass for a live one when the row comes back."""
        gone = [t for t in self.watched if t not in topics]
        for topic in gone:
            self.rates.pop(topic, None)
        self.watched = list(topics)
        return gone

    def answered(self, result: Mapping[str, Any] | None) -> None:
        """The server's answer to `watch_rates`."""
        # why a topic has no rate (nobody publishes it, its type is not installed)
        self.unmeasured = dict((result or {}).get("unmeasured") or {})
        # the minutes the server kept of each (another client watching it, or we before)
        for topic, kept in ((result or {}).get("history") or {}).items():
            if topic in self.watched and len(kept) > len(self.history.get(topic, ())):
                self.history[topic] = deque((r or 0.0 for r in kept), maxlen=RATE_HISTORY)
        for topic in [t for t in self.history if t not in self.watched]:
            del self.history[topic]

    def take(self, rates: Mapping[str, Any]) -> list[str]:
        """A `rates` event: the topics whose figures it brought, watched still."""
        taken = []
        for topic, values in rates.items():
            if not isinstance(values, Mapping) or topic not in self.watched:
                continue  # a figure sent before we stopped watching that row
            self.rates[topic] = dict(values)
            self.history.setdefault(topic, deque(maxlen=RATE_HISTORY)).append(
                float(values.get("rate_hz") or 0.0))
            taken.append(topic)
        return taken


class TopicEcho:
    """The echo of one topic under the detail: which topic, its newest messages, and the
    requests that start and stop it on the server."""

    def __init__(self, panel: TopicsPanel) -> None:
        self.panel = panel
        self.topic: str | None = None
        self.messages: deque[str] = deque(maxlen=ECHO_KEEP)

    def toggle(self, topic: str) -> None:
        """Echoes `topic`, or stops when it is the one echoed."""
        stop = self.topic == topic
        if self.topic is not None:
            self.stop()
        if not stop:
            self.topic = topic
            self.messages.clear()
            self.panel.run_worker(self._start(topic), group="topics-echo", exit_on_error=False)

    async def _start(self, topic: str) -> None:
        try:
            await self.panel.request(EchoStart(topic=topic, max_per_s=ECHO_PER_S))
        except Exception as exc:
            if self.topic == topic:
                self.topic = None
                self.panel.note(f"cannot echo {topic}: {_one_line(exc)}", ok=False)
                self.panel.show_detail()

    def stop(self) -> None:
        topic, self.topic = self.topic, None
        self.messages.clear()
        if topic is not None:
            self.panel.run_worker(self._stop(topic), group="topics-echo", exit_on_error=False)

    async def _stop(self, topic: str) -> None:
        try:
            await self.panel.request(EchoStop(topic=topic))
        except Exception:
            pass  # the echo ended by itself (its count, the topic gone): nothing to stop

    def take(self, data: Mapping[str, Any]) -> bool:
        """An `echo` event: a message of the echoed topic, as YAML (False: of another)."""
        if data.get("topic") != self.topic:
            return False
        # each message's YAML ends with its `---`; they are joined with one again
        self.messages.append(str(data.get("text") or "").rstrip().removesuffix("---").rstrip())
        return True

    def lines(self, room: int) -> list[tuple[str, str]]:
        """The echo's title and its newest lines that fit in `room` lines."""
        messages = "\n---\n".join(self.messages) if self.messages else "waiting for a message"
        echoed = [(line, "") for line in messages.splitlines()]
        # the newest lines are what an echo is for: the oldest go first
        return [(f"echo {self.topic} (e stops):", "bold"),
                *echoed[max(0, len(echoed) - (room - 1)):]]


class RateTrend(Horizontal):
    """The selected topic's rate over the last minutes, as a sparkline (Textual's), with
    its span and its top; hidden for a topic with fewer than two rates."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.data: list[float] = []
        """The rates drawn."""

    def compose(self) -> ComposeResult:
        yield Static("rate, last minutes", id="tpc-trend-label")
        yield Static("", id="tpc-spark")

    def show(self, history: deque[float] | None) -> None:
        shown = history is not None and len(history) >= 2
        self.set_class(shown, "shown")
        if shown and history is not None and list(history) != self.data:
            # from zero to the max said beside it: a steady rate draws steady bars
            data = self.data = list(history)
            self.query_one("#tpc-trend-label", Static).update(
                f"rate, last {len(data) // 60 or len(data)} "
                f"{'min' if len(data) >= 60 else 's'} (0 to {rate_text(max(data))})")
            spark = self.query_one("#tpc-spark", Static)
            spark.update(units.spark(data, max(spark.size.width, 10)))


def styled(lines: list[tuple[str, str]]) -> Text:
    """Lines of text, each with its style ("" for none), as one Text."""
    text = Text("\n".join(line for line, _ in lines), no_wrap=True, overflow="ellipsis")
    position = 0
    for line, style in lines:
        if style:
            text.stylize(style, position, position + len(line))
        position += len(line) + 1
    return text


class TopicsPanel(Vertical):
    class PlotAsked(Message):
        """`p` on a topic: the app opens its plot (tui/inspector.py)."""

        def __init__(self, topic: str) -> None:
            super().__init__()
            self.topic = topic

    class RecordAsked(Message):
        """`w` on a topic: the app records it, or stops its recording (tui/recording.py)."""

        def __init__(self, topic: str | None) -> None:
            super().__init__()
            self.topic = topic

    DEFAULT_CSS = """
    TopicsPanel #tpc-bar { height: 1; }
    TopicsPanel #tpc-rec { width: auto; padding: 0 1; color: $error; }
    TopicsPanel #tpc-filter { width: 1fr; }
    TopicsPanel #tpc-scope { width: auto; padding: 0 1; color: $text-muted; }
    /* a long type is cut (the detail shows it whole): no horizontal scrollbar to repaint */
    TopicsPanel #tpc-table { height: 1fr; overflow-x: hidden; }
    TopicsPanel #tpc-note { height: 1; color: $text-muted; }
    TopicsPanel #tpc-note.error { color: $error; }
    TopicsPanel #tpc-trend { height: 1; display: none; }
    TopicsPanel #tpc-trend.shown { display: block; }
    TopicsPanel #tpc-trend-label { width: auto; padding: 0 1; color: $text-muted; }
    TopicsPanel #tpc-spark { width: 1fr; height: 1; }
    TopicsPanel #tpc-detail { height: 1fr; padding: 0 1; border-top: tall $panel; }
    """
    BINDINGS = [
        Binding("e", "echo", "Echo", tooltip="Show the selected topic's messages (e again "
                "stops)"),
        Binding("p", "plot", "Plot", tooltip="Plot the selected topic's numeric fields"),
        Binding("w", "record", "Record", tooltip="Record the selected topic into an MCAP "
                "file here (w again stops)"),
        Binding("slash", "filter", "Filter", tooltip="Filter topics by name or type"),
        Binding("x", "all_topics", "All topics", tooltip="Back from one node's topics to all"),
        Binding("u", "update", "Update", show=False, tooltip="Ask for the topic list now"),
    ]

    def __init__(self, request: Request, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.request = request
        self.entries: dict[str, dict[str, Any]] = {}
        """The last `topics` answer, by topic name."""
        self.shown: list[str] = []
        """The table's rows (topic names), in order."""
        self.cells: dict[tuple[str, str], str] = {}
        """The text of every cell, so an unchanged one is not sent to the terminal again."""
        self.measured = TopicRates()
        self.node: str | None = None
        """A node whose topics only are listed (the Nodes tab's `o`)."""
        self.selected: str | None = None
        self.echo = TopicEcho(self)
        self.active = False
        self.ticks = 0
        self.problem_mark = "x" if ascii_terminal() else "✗"
        self._detail_text = ""
        self._note = ("", True)

    def compose(self) -> ComposeResult:
        with Horizontal(id="tpc-bar"):
            yield Field(placeholder="/ filter topics (name or type)", id="tpc-filter",
                        compact=True, leave_on_enter=True)
            yield Static("all topics", id="tpc-scope")
            yield Static("", id="tpc-rec")  # a recording and its size (tui/recording.py)
        yield QuietTable(id="tpc-table", cursor_type="row", zebra_stripes=False)
        yield Static("", id="tpc-note")
        yield RateTrend(id="tpc-trend")
        yield Static("", id="tpc-detail")

    def on_mount(self) -> None:
        table = self.query_one(QuietTable)
        for key, title, width in COLUMNS:
            table.add_column(title, key=key, width=width)
        self.timer = self.set_interval(1.0, self.tick, pause=True)

    @property
    def table(self) -> QuietTable:
        return self.query_one(QuietTable)

    # --- shown or not ------------------------------------------------------------------------

    def set_shown(self, shown: bool) -> None:
        """The tab is on screen (the list refreshes, rates are measured) or left (the
        server stops measuring and echoing for us)."""
        if shown == self.active:
            return
        self.active = shown
        if shown:
            self.ticks = 0
            self.timer.resume()
            self.refresh_topics()
        else:
            self.timer.pause()
            self.watch_visible([])
            if self.echo.topic is not None:
                self.stop_echo()

    def tick(self) -> None:
        self.ticks += 1
        if self.ticks % REFRESH_TICKS == 0:
            self.refresh_topics()
        else:
            self.watch_visible(self.rows_on_screen())

    def show_node(self, node: str | None) -> None:
        """Lists only the topics `node` publishes or subscribes (None: all)."""
        self.node = node
        if node:  # an old filter would hide the node's own topics: `o` shows them all
            self.query_one("#tpc-filter", Input).value = ""
        self.query_one("#tpc-scope", Static).update(
            Text(f"node {node} (x: all)" if node else "all topics"))
        self.entries = {}
        self._fill()
        self.refresh_topics()
        self.refresh_bindings()

    # --- the list ----------------------------------------------------------------------------

    @work(group="topics-list", exclusive=True, exit_on_error=False)
    async def refresh_topics(self) -> None:
        try:
            result = await self.request(Topics(node=self.node or None))
        except Exception as exc:  # a session without the inspector, a node that is gone
            self.note(f"cannot list topics: {_one_line(exc)}", ok=False)
            return
        self.entries = {str(t["name"]): t for t in result.get("topics") or []}
        self._fill()

    def _matching(self) -> list[str]:
        term = self.query_one("#tpc-filter", Input).value.strip().lower()
        return sorted(name for name, entry in self.entries.items() if not term
                      or term in name.lower()
                      or any(term in str(t).lower() for t in entry.get("types") or []))

    def _fill(self) -> None:
        """The rows in place: cells updated where their text changed; the table is rebuilt
        only when the set of rows changes (a topic came or went, the filter changed)."""
        table = self.table
        names = self._matching()
        if names != self.shown:
            # the row under the cursor now: `selected` follows it by a message, which a
            # listing that lands first would otherwise undo (a topic came as one moved)
            keep = self.shown[table.cursor_row] if table.cursor_row < len(self.shown) \
                else self.selected
            table.clear()
            self.cells = {}
            for name in names:
                values = self._values(name)
                table.add_row(*values.values(), key=name)
                self.cells.update({(name, k): str(v) for k, v in values.items()})
            self.shown = names
            if keep in names:
                table.move_cursor(row=names.index(keep), animate=False)
            elif names:
                self.selected = names[table.cursor_row if table.cursor_row < len(names) else 0]
            else:
                self.selected = None
        else:
            for name in names:
                for key, value in self._values(name).items():
                    self._set(name, key, value)
        count = len(self.entries)
        noun = "topic" if count == 1 else "topics"
        what = f"{len(names)} of {count} {noun}" if len(names) != count else f"{count} {noun}"
        if not count:  # an empty graph is often one not discovered yet
            what = discovering("topic", REFRESH_TICKS)
        self.note(f"{what}; e echo, p plot, / filter" + (", x all topics" if self.node else ""))
        self.watch_visible(self.rows_on_screen())
        self.show_detail()

    def _values(self, name: str) -> dict[str, Any]:
        return row_values(name, self.entries.get(name, {}), self.measured.rates.get(name, {}),
                          self.problem_mark)

    def _set(self, row: str, column: str, value: Any) -> None:
        text = str(value)
        if self.cells.get((row, column)) != text:
            self.cells[(row, column)] = text
            self.table.set_cell(row, column, value)

    @on(Input.Changed, "#tpc-filter")
    def _filter(self) -> None:
        self._fill()

    @on(DataTable.RowHighlighted, "#tpc-table")
    def _highlighted(self, event: DataTable.RowHighlighted) -> None:
        self.selected = str(event.row_key.value)
        self.show_detail()
        self.watch_visible(self.rows_on_screen())  # the cursor may have scrolled the table

    def rows_on_screen(self) -> list[str]:
        """The topics of the rows on screen now."""
        table = self.table
        first = int(table.scroll_offset.y)
        rows = max(0, table.size.height - (1 if table.show_header else 0))
        return self.shown[first:first + rows]

    # --- rates -------------------------------------------------------------------------------

    @property
    def watched(self) -> list[str]:
        """The topics the server measures for us (the rows on screen)."""
        return self.measured.watched

    def watch_visible(self, topics: list[str]) -> None:
        """Asks the server to measure these topics for us, when they changed."""
        if not self.active:
            topics = []
        if topics == self.measured.watched:
            return
        for gone in self.measured.watch(topics):
            if gone in self.shown:
                self._set(gone, "rate", "")
                self._set(gone, "bw", "")
        self._send_watch(list(topics))

    @work(group="topics-watch", exit_on_error=False)
    async def _send_watch(self, topics: list[str]) -> None:
        try:
            result = await self.request(WatchRates(topics=topics))
        except Exception as exc:
            if topics:
                self.note(f"cannot measure rates: {_one_line(exc)}", ok=False)
            return
        self.measured.answered(result)
        self.show_detail()

    @property
    def rates(self) -> dict[str, dict[str, Any]]:
        """The last figures of the watched topics, by topic (the tests read them)."""
        return self.measured.rates

    def show_rates(self, rates: Mapping[str, Any]) -> None:
        """A `rates` event: the cells of these topics, where their text changed."""
        for topic in self.measured.take(rates):
            if topic in self.shown:
                values = self.measured.rates[topic]
                self._set(topic, "rate", rate_text(values.get("rate_hz")))
                self._set(topic, "bw", bytes_text(values.get("bytes_per_s"), "/s"))
        if self.selected in rates:
            self.show_detail()

    # --- echo --------------------------------------------------------------------------------

    def action_echo(self) -> None:
        if self.selected is not None:
            self.echo.toggle(self.selected)
            self.show_detail()

    @property
    def echo_topic(self) -> str | None:
        """The topic echoed under the detail, if any."""
        return self.echo.topic

    def stop_echo(self) -> None:
        self.echo.stop()
        self.show_detail()

    def show_echo(self, data: Mapping[str, Any]) -> None:
        """An `echo` event: a message of the echoed topic, as YAML."""
        if self.echo.take(data):
            self.show_detail()

    def action_plot(self) -> None:
        if self.selected is not None:
            self.post_message(self.PlotAsked(self.selected))

    def action_record(self) -> None:
        self.post_message(self.RecordAsked(self.selected))

    def show_recording(self, text: str) -> None:
        self.query_one("#tpc-rec", Static).update(text)

    # --- the selected topic ------------------------------------------------------------------

    def show_detail(self) -> None:
        detail = self.query_one("#tpc-detail", Static)
        name = self.selected
        entry = self.entries.get(name or "")
        lines: list[tuple[str, str]] = []
        if name is None or entry is None:
            lines.append(("Pick a topic: its publishers, subscribers and QoS show here.",
                          "dim"))
        else:
            lines += self._topic_lines(name, entry)
        height = max(1, detail.size.height or 1)
        if self.echo.topic is not None:
            lines += self.echo.lines(height - len(lines))
        text = styled(lines[:height])
        if text.plain != self._detail_text:  # an unchanged detail is not sent again
            self._detail_text = text.plain
            detail.update(text)
        self.query_one(RateTrend).show(self.measured.history.get(self.selected or ""))

    def _topic_lines(self, name: str, entry: Mapping[str, Any]) -> list[tuple[str, str]]:
        """The selected topic's head line (types, rate), its problems, and its endpoints
        unless an echo takes the room."""
        rate = self.measured.rates.get(name)
        head = f"{name}  {', '.join(entry.get('types') or [])}"
        watched = name in self.measured.watched
        if rate and watched:
            head += f"  {rate_text(rate.get('rate_hz'))}  " \
                    f"{bytes_text(rate.get('bytes_per_s'), '/s')}"
        lines = [(head, "bold")]
        if name in self.measured.unmeasured and watched:
            lines.append((f"no rate: {self.measured.unmeasured[name]}", "yellow"))
        lines += [(f"{self.problem_mark} {p}", "red") for p in entry.get("qos_problems") or []]
        if self.echo.topic is None:  # while echoing, the messages take the room
            for key in ("publishers", "subscribers"):
                endpoints = entry.get(key) or []
                lines.append((f"{key}: {len(endpoints) or 'none'}", ""))
                lines += [(endpoint_line(e), "") for e in endpoints]
        return lines

    @property
    def trend_data(self) -> list[float]:
        """The rates the sparkline draws (the tests read them)."""
        return self.query_one(RateTrend).data

    def note(self, text: str, ok: bool = True) -> None:
        if (text, ok) != self._note:
            self._note = (text, ok)
            note = self.query_one("#tpc-note", Static)
            note.update(Text(text))
            note.set_class(not ok, "error")

    @property
    def detail_text(self) -> str:
        """What the detail area shows now (the tests read it)."""
        return self._detail_text

    # --- keys --------------------------------------------------------------------------------

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "all_topics":
            return self.node is not None  # shown only while one node's topics are listed
        return True

    def action_filter(self) -> None:
        # at once, not on the next tick: the keys typed right after go into the field
        self.screen.set_focus(self.query_one("#tpc-filter", Field))

    def action_all_topics(self) -> None:
        if self.node is not None:
            self.show_node(None)

    def action_update(self) -> None:
        self.refresh_topics()


def _one_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]
