"""The plot screen's two pickers: the fields to plot (each one marked `[X]` when chosen, so
the mark reads without colour) and a topic to add to the plot (of any session it reaches).
"""

from __future__ import annotations

from typing import Any

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.widgets import OptionList, Static
from textual.widgets.option_list import Option

PICKER_CSS = """
{name} {{ align: center middle; }}
{name} > Vertical {{ width: 64; max-width: 100%; height: 80%; padding: 0 1;
                     border: round $primary; background: $surface; }}
{name} OptionList {{ height: 1fr; }}
{name} .pick-help {{ height: 1; color: $text-muted; }}
"""


class FieldPicker(ModalScreen[list[Any] | None]):
    """Fields by label, the plotted ones ticked: space ticks (or unticks) the highlighted
    one, enter plots the ticked ones, escape leaves them as they were."""

    DEFAULT_CSS = PICKER_CSS.format(name="FieldPicker")
    # before the list's own enter (which selects the highlighted option)
    BINDINGS = [Binding("enter", "done", "Plot", priority=True),
                Binding("space", "tick", "Tick", priority=True),
                Binding("escape", "cancel", "Cancel")]

    def __init__(self, items: list[tuple[Any, str]], chosen: list[Any],
                 title: str = "") -> None:
        """`items`: (key, label) in order; `chosen`: the keys ticked first."""
        super().__init__()
        self.items = items
        self.ticked = [key for key, _ in items if key in chosen]
        self.title_text = title

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static(Text(self.title_text or "the fields to plot"), classes="pick-help")
            yield Static(Text("space: tick [X] or untick [ ], enter: plot the ticked ones"),
                         classes="pick-help")
            yield OptionList(*[Option(self._prompt(i), id=str(i))
                               for i in range(len(self.items))])

    def _prompt(self, index: int) -> Text:
        key, label = self.items[index]
        mark = "[X] " if key in self.ticked else "[ ] "
        return Text.assemble((mark, "bold" if key in self.ticked else "dim"), label)

    @property
    def marks(self) -> list[str]:
        """Each line as drawn, `[X] label` or `[ ] label` (the tests read them)."""
        return [self._prompt(i).plain for i in range(len(self.items))]

    def action_tick(self) -> None:
        options = self.query_one(OptionList)
        index = options.highlighted
        if index is None:
            return
        key = self.items[index][0]
        if key in self.ticked:
            self.ticked.remove(key)
        else:
            self.ticked.append(key)
        options.replace_option_prompt_at_index(index, self._prompt(index))

    def action_done(self) -> None:
        order = [key for key, _ in self.items]
        self.dismiss(sorted(self.ticked, key=order.index))

    def action_cancel(self) -> None:
        self.dismiss(None)


class TopicPicker(ModalScreen[tuple[str, str] | None]):
    """The topics of the sessions a plot reaches: enter adds the highlighted one."""

    DEFAULT_CSS = PICKER_CSS.format(name="TopicPicker")
    BINDINGS = [Binding("enter", "done", "Add", priority=True),
                Binding("escape", "cancel", "Cancel")]

    def __init__(self, topics: list[tuple[str, str, str]]) -> None:
        """`topics`: (session, topic, type); the session `""` when there is one."""
        super().__init__()
        self.topics = topics

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static("enter: add the topic (its fields next)", classes="pick-help")
            yield OptionList(*[Option(Text.assemble(
                (f"{session} ", "bold") if session else "", topic, (f"  {kind}", "dim")))
                for session, topic, kind in self.topics])

    def action_done(self) -> None:
        index = self.query_one(OptionList).highlighted
        if index is None:
            self.dismiss(None)
            return
        session, topic, _ = self.topics[index]
        self.dismiss((session, topic))

    def action_cancel(self) -> None:
        self.dismiss(None)
