"""Modal screens: quit confirmation while nodes run, and the keys."""

from __future__ import annotations

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen
from textual.widgets import Button, Static

KEYS = """\
[b]Anywhere[/b] (in a text field, esc leaves it first)
  1 2 3 4   tabs: Nodes Args Services Params   ? help
  q ctrl+c  quit (asks while nodes run;        ctrl+p palette
            again while stopping: kill now)
  F5        apply edited arguments
  d         detach: the launch runs on (tuilaunch attach)
[b]Nodes[/b] (arrows: tree; tab: into the pane)
  s r t     stop / restart / start node or group
  i         type into the node's terminal (every key, ctrl+c too) until ctrl+]
  g         restart the node under a tool (gdb, valgrind...); r: plain again
  c         the node's exact command line (y copies it)
  a         all nodes' output
  / n N     search, next / previous match; esc clears
  l  \\      level filter / text filter
  G         follow the newest line (end too)
  z T f     wrap / timestamps / lines as printed
  < >       narrower / wider tree
  w y       save the pane / copy it (OSC 52)
[b]Args, Services, Params[/b]
  tab shift+tab between fields; enter calls or sets
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


class QuitScreen(ModalScreen[bool]):
    DEFAULT_CSS = """
    QuitScreen { align: center middle; }
    QuitScreen > Vertical { width: 60; max-width: 100%; height: auto; padding: 1 2;
                            border: round $warning; background: $surface; }
    QuitScreen Horizontal { height: 3; }
    """
    BINDINGS = [Binding("y", "answer(True)", "Yes"), Binding("n,escape", "answer(False)", "No")]

    def __init__(self, running: list[str]) -> None:
        super().__init__()
        self.running = running

    def compose(self) -> ComposeResult:
        names = ", ".join(self.running[:8]) + (" ..." if len(self.running) > 8 else "")
        with Vertical():
            yield Static(f"{len(self.running)} processes still run: {names}\n"
                         "Stop them all and quit?")
            with Horizontal():
                yield Button("Stop and quit (y)", id="yes", variant="error")
                yield Button("Keep running (n)", id="no")

    def action_answer(self, answer: bool) -> None:
        self.dismiss(answer)

    @on(Button.Pressed)
    def _pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id == "yes")
