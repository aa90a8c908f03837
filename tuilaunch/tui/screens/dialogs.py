"""Modal screens: quit confirmation while nodes run, questions, and the keys."""

from __future__ import annotations

from typing import Any, TypeVar

from rich.text import Text
from textual import events, on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.screen import ModalScreen
from textual.widgets import Button, Input, OptionList, Static
from textual.widgets.option_list import Option

from .fields import Field

KEYS = """\
[b]Anywhere[/b] (a text field: esc leaves it first)
  1-5  tabs: Nodes Args Services Params Topics    ? F1  these keys
  q ctrl+c  quit (asks while nodes run; d there: detach; again: kill now)
  F5   apply edited arguments   d  detach   ctrl+p :  command palette
  tab shift+tab  next / previous widget, into the fields; esc: back
[b]Nodes[/b]
  s r t  stop / restart / start   a      all nodes' output
  / n N  search, next / previous  l \\    level / text filter
  G end  follow the newest line   z T f  wrap / time / as printed
  < >    narrower / wider tree    w y    save / copy the pane (OSC 52)
  o      the node's topics        L      the node's log level
  i      type into it (ctrl+] ends)   g  restart it under a tool (gdb...)
  c      its exact command line (y: copy)
  rows: CPU% and memory (wide tree); UPmem memory keeps growing;
        XQOS: a publisher/subscriber pair whose QoS cannot talk
[b]Topics[/b]  / filter  e echo (again: stop)  x all topics (after o)  u update
  p      plot the topic's fields: w window  space pause  f fields  q back
[b]Services, Params[/b]  / filter the list; enter: call, set
[b]Params[/b]  w o  write the node's parameters to a file / load a file
"""


def keys_text(ascii_only: bool) -> str:
    """The keys, with the marks the tree draws on this terminal."""
    up, cross = ("^", "x") if ascii_only else ("↑", "✗")
    return KEYS.replace("UPmem", f"{up}mem").replace("XQOS", f"{cross}qos")


ResultT = TypeVar("ResultT")

ANSWER_KEYS = frozenset({"enter", "tab", "shift+tab", "left", "right", "ctrl+c"})
"""Keys a yes/no question takes besides its own letters: Enter presses the button with the
focus, the others move it; ctrl+c quits as anywhere."""


def dialog_css(screen: str, width: int, border: str = "primary", more: str = "") -> str:
    """A dialog's look: a box of `width` columns (at most the terminal's) in the middle of the
    screen, framed in the theme's `border` colour; `more`: rules of its own."""
    return (f"{screen} {{ align: center middle; }}\n"
            f"{screen} > Vertical {{ width: {width}; max-width: 100%; height: auto; "
            f"padding: 1 2; border: round ${border}; background: $surface; }}\n{more}\n")


class HelpScreen(ModalScreen[None]):
    """The keys, over the screen; scrolls when the terminal is short."""

    DEFAULT_CSS = """
    HelpScreen { align: center middle; }
    HelpScreen > VerticalScroll { width: auto; max-width: 100%; height: auto;
                                  max-height: 100%; padding: 0 1;
                                  border: round $primary; background: $surface; }
    HelpScreen Static { width: auto; }
    """
    BINDINGS = [Binding("escape,q,question_mark,f1", "dismiss", "Close")]

    def compose(self) -> ComposeResult:
        from .tree_panel import ascii_terminal

        with VerticalScroll():
            yield Static(keys_text(ascii_terminal()))


class QuestionScreen(ModalScreen[ResultT]):
    """A question in a box over the screen (`dialog_css`), the ways to answer it below."""

    def __init__(self, question: str) -> None:
        super().__init__()
        self.question = question

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static(Text(self.question))
            yield from self.answers()

    def answers(self) -> ComposeResult:
        raise NotImplementedError


class ConfirmScreen(QuestionScreen[bool]):
    """A yes/no question with the keys on its buttons. Its yes stops, restarts or quits
    something: the question opens with No focused, so an Enter alone (the end of a line
    typed for a node, a reflex) changes nothing; `y`, or Enter once the focus is moved to
    the yes button, does it."""

    DEFAULT_CSS = dialog_css("ConfirmScreen", 60, "warning",
                             more="ConfirmScreen Horizontal { height: 3; }")
    BINDINGS = [Binding("y", "answer(True)", "Yes"), Binding("n,escape", "answer(False)", "No")]

    quit_question: bool = False
    """It asks about quitting: q or ctrl+c again does not ask a second time."""

    def __init__(self, question: str, yes: str = "Yes (y)", no: str = "No (n)") -> None:
        super().__init__(question)
        self.yes = yes
        self.no = no

    def answers(self) -> ComposeResult:
        with Horizontal():
            yield Button(self.yes, id="yes", variant="error")
            yield Button(self.no, id="no")

    def on_mount(self) -> None:
        self.query_one("#no", Button).focus()  # the safe answer (see the class)

    def action_answer(self, answer: bool) -> None:
        self.dismiss(answer)

    @on(Button.Pressed)
    def _pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id == "yes")

    def on_key(self, event: events.Key) -> None:
        only_answer_keys(self, event)


class QuitScreen(ModalScreen[str]):
    """Quit while processes run: stop them all ("stop"), keep running ("keep"), or, for a
    session, leave it running without this window ("detach"). The same keys on a local and
    a remote session (`host`): `y` stops, `d` detaches, `n` and esc keep running; it opens
    with Keep running focused, so an Enter alone stops nothing and leaves nothing."""

    DEFAULT_CSS = dialog_css("QuitScreen", 64, "warning",
                             more="QuitScreen Horizontal { height: auto; }\n"
                                  "QuitScreen > Vertical.-narrow { padding: 0 1; }\n"
                                  "QuitScreen .-narrow Button { min-width: 0; width: auto; "
                                  "margin-right: 1; }")
    BINDINGS = [Binding("y", "answer('stop')", "Stop and quit"),
                Binding("n,escape", "answer('keep')", "Keep running"),
                Binding("d", "answer('detach')", "Detach", show=False)]

    quit_question = True

    def __init__(self, running: list[str], detach: bool = False,
                 host: str | None = None) -> None:
        super().__init__()
        self.running = running
        self.detach = detach
        self.host = host

    def compose(self) -> ComposeResult:
        names = ", ".join(self.running[:8]) + (" ..." if len(self.running) > 8 else "")
        where = f" on {self.host}" if self.host else ""
        if len(self.running) == 1:
            question = f"1 process still runs{where}: {names}\nStop it and quit?"
        else:
            question = f"{len(self.running)} processes still run{where}: {names}\n" \
                       "Stop them all and quit?"
        if self.detach:
            there = " there" if self.host else ""
            question += f"\nOr detach: they run on{there}, tuilaunch attach comes back to " \
                        "them."
        # a narrow terminal (40 columns) gets short, one-line buttons: all three fit, Keep
        # running among them, where the full ones ran off the screen's edge
        narrow = self.app.size.width < 66
        with Vertical(classes="-narrow" if narrow else ""):
            yield Static(Text(question))
            with Horizontal():
                yield Button("Stop (y)" if narrow else "Stop and quit (y)", id="stop",
                             variant="error", compact=narrow)
                if self.detach:
                    yield Button("Detach (d)", id="detach", variant="primary", compact=narrow)
                yield Button("Keep (n)" if narrow else "Keep running (n)", id="keep",
                             compact=narrow)

    def on_mount(self) -> None:
        self.query_one("#keep", Button).focus()  # the safe answer (see the class)

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "answer" and parameters == ("detach",) and not self.detach:
            return False
        return True

    def action_answer(self, answer: str) -> None:
        self.dismiss(answer)

    @on(Button.Pressed)
    def _pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id or "keep")

    def on_key(self, event: events.Key) -> None:
        only_answer_keys(self, event)


def only_answer_keys(screen: ModalScreen[Any], event: events.Key) -> None:
    """Only a question's own keys answer it: the others stop here, before the app's
    bindings (a burst typed for a node, `iquit yes`, must not quit through the dialog, and
    a space must not press the button that has the focus)."""
    if event.key not in screen._bindings.key_to_bindings and event.key not in ANSWER_KEYS:
        event.stop()
        event.prevent_default()


class ChoiceScreen(QuestionScreen[str | None]):
    """One of a few answers, picked with arrows and enter or with its first letter."""

    DEFAULT_CSS = dialog_css("ChoiceScreen", 60,
                             more="ChoiceScreen OptionList { height: auto; max-height: 10; }")
    BINDINGS = [Binding("escape", "dismiss(None)", "Cancel")]

    def __init__(self, question: str, choices: list[str], current: str | None = None) -> None:
        super().__init__(question)
        self.choices = choices
        self.current = current

    def answers(self) -> ComposeResult:
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


class PathScreen(QuestionScreen[str | None]):
    """Asks for a file path, offering one; enter takes it, escape cancels."""

    DEFAULT_CSS = dialog_css("PathScreen", 70)
    BINDINGS = [Binding("escape", "dismiss(None)", "Cancel")]

    def __init__(self, question: str, default: str = "") -> None:
        super().__init__(f"{question} (enter: ok, esc: cancel)")
        self.default = default

    def answers(self) -> ComposeResult:
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
