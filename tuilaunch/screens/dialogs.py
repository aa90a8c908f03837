"""Modal screens: quit confirmation while nodes run, and the keys."""

from __future__ import annotations

from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen
from textual.widgets import Button, Static

KEYS = """\
[b]Anywhere[/b]
  1 2 3 4    tabs: Nodes, Args, Services, Params     ?       this help
  q ctrl+c   quit (asks while nodes run)             ctrl+p  command palette
  F5         apply edited arguments (relaunches only what they change)
  d          detach: the launch runs on; tuilaunch attach opens it again
[b]Nodes[/b]  (arrows move in the tree, enter folds a group)
  s r t      stop / restart / start the selected node or group
  a          output of all nodes
  / n N      search the pane, next / previous match  esc     clear
  l          level filter: DEBUG+ INFO+ WARN+ ERROR+ FATAL
  \\          text filter: only lines containing ...
  G          follow the newest line
  w y        save the pane to a file / copy it (OSC 52)
[b]Args, Services, Params[/b]
  tab / shift+tab between fields; enter calls a service or sets a parameter
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
