"""Modal screens: quit confirmation while nodes run, questions, and the keys."""

from __future__ import annotations

from rich.text import Text
from textual import events, on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen
from textual.widgets import Button, Input, OptionList, Static
from textual.widgets.option_list import Option

from .fields import Field

KEYS = """\
[b]Anywhere[/b] (in a text field, esc leaves it first)
  1-5     tabs: Nodes Args Services Params Topics   ? help  ctrl+p palette
  q ctrl+c  quit (asks while nodes run; again while stopping: kill now)
  F5      apply edited arguments   d  detach (tuilaunch attach: back)
[b]Nodes[/b] (arrows: tree; tab: into the pane)
  s r t   stop / restart / start   a      all nodes' output
  / n N   search, next / previous  l \\    level / text filter
  G end   follow the newest line   z T f  wrap / time / as printed
  < >     narrower / wider tree    w y    save / copy the pane (OSC 52)
  o       the node's topics        L      the node's log level
  i       type into it (ctrl+] ends)  g    restart it under a tool (gdb...)
  c       its exact command line (y: copy)
  rows: CPU% and memory (wide tree), ↑mem memory keeps growing,
        ✗qos in a publisher/subscriber pair whose QoS cannot talk
[b]Topics[/b] (rates for the rows on screen)
  /  filter   e  echo (again: stop)   x  all topics (after o)   u  update
[b]Params[/b]  w o  write the node's parameters to a file / load a file
[b]Args, Services, Params[/b]  tab shift+tab between fields; enter: call, set
"""


class HelpScreen(ModalScreen[None]):
    DEFAULT_CSS = """
    HelpScreen { align: center middle; }
    HelpScreen > Static { width: auto; max-width: 100%; height: auto; padding: 1 2;
                          border: round $primary; background: $surface; }
    """
    BINDINGS = [Binding("escape,q,question_mark", "dismiss", "Close")]

    def compose(self) -> ComposeResult:
        yield Static(KEYS)


class ConfirmScreen(ModalScreen[bool]):
    """A yes/no question with the keys on its buttons."""

    DEFAULT_CSS = """
    ConfirmScreen { align: center middle; }
    ConfirmScreen > Vertical { width: 60; max-width: 100%; height: auto; padding: 1 2;
                               border: round $warning; background: $surface; }
    ConfirmScreen Horizontal { height: 3; }
    """
    BINDINGS = [Binding("y", "answer(True)", "Yes"), Binding("n,escape", "answer(False)", "No")]

    def __init__(self, question: str, yes: str = "Yes (y)", no: str = "No (n)") -> None:
        super().__init__()
        self.question = question
        self.yes = yes
        self.no = no

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static(Text(self.question))
            with Horizontal():
                yield Button(self.yes, id="yes", variant="error")
                yield Button(self.no, id="no")

    def action_answer(self, answer: bool) -> None:
        self.dismiss(answer)

    @on(Button.Pressed)
    def _pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id == "yes")


class QuitScreen(ConfirmScreen):
    """Quitting while processes run: stop them all and quit, or keep running."""

    def __init__(self, running: list[str]) -> None:
        names = ", ".join(running[:8]) + (" ..." if len(running) > 8 else "")
        super().__init__(f"{len(running)} processes still run: {names}\nStop them all and quit?",
                         yes="Stop and quit (y)", no="Keep running (n)")
        self.running = running


class ChoiceScreen(ModalScreen[str | None]):
    """One of a few answers, picked with arrows and enter or with its first letter."""

    DEFAULT_CSS = """
    ChoiceScreen { align: center middle; }
    ChoiceScreen > Vertical { width: 60; max-width: 100%; height: auto; padding: 1 2;
                              border: round $primary; background: $surface; }
    ChoiceScreen OptionList { height: auto; max-height: 10; }
    """
    BINDINGS = [Binding("escape", "dismiss(None)", "Cancel")]

    def __init__(self, question: str, choices: list[str], current: str | None = None) -> None:
        super().__init__()
        self.question = question
        self.choices = choices
        self.current = current

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static(Text(self.question))
            yield OptionList(*(Option(f"{c[0]}  {c}", id=c) for c in self.choices))

    def on_mount(self) -> None:
        options = self.query_one(OptionList)
        if self.current in self.choices:
            options.highlighted = self.choices.index(self.current)
        options.focus()

    def on_key(self, event: events.Key) -> None:
        for choice in self.choices:
            if event.character == choice[0]:
                event.stop()
                self.dismiss(choice)
                return

    @on(OptionList.OptionSelected)
    def _picked(self, event: OptionList.OptionSelected) -> None:
        self.dismiss(str(event.option.id))


class PathScreen(ModalScreen[str | None]):
    """Asks for a file path, offering one; enter takes it, escape cancels."""

    DEFAULT_CSS = """
    PathScreen { align: center middle; }
    PathScreen > Vertical { width: 70; max-width: 100%; height: auto; padding: 1 2;
                            border: round $primary; background: $surface; }
    """
    BINDINGS = [Binding("escape", "dismiss(None)", "Cancel")]

    def __init__(self, question: str, default: str = "") -> None:
        super().__init__()
        self.question = question
        self.default = default

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static(Text(f"{self.question} (enter: ok, esc: cancel)"))
            yield PathField(value=self.default, id="path-input")

    def on_mount(self) -> None:
        self.query_one(Input).focus()

    @on(Input.Submitted)
    def _submitted(self, event: Input.Submitted) -> None:
        event.stop()
        path = event.value.strip()
        self.dismiss(path or None)


class PathField(Field):
    """The path dialog's field: escape cancels the dialog (a Field would leave the field
    for the app's tab instead)."""

    async def _on_key(self, event: events.Key) -> None:
        if event.key == "escape":
            event.stop()
            event.prevent_default()
            self.screen.dismiss(None)
            return
        await super()._on_key(event)
