"""The line that takes the keys while typing into a node, the question whether to give a node
a terminal to type into, the prompt for a tool to run a node under (gdb, valgrind...), and
the node's exact command line to copy."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rich.text import Text
from textual import events, on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.suggester import SuggestFromList
from textual.widgets import Input, OptionList, Static

from ..key_order import KeyHold, hold_keys
from .dialogs import ConfirmScreen, dialog_css

KNOWN_PREFIXES = ("gdb -q -ex run --args", "valgrind --leak-check=full",
                  "python3 -m pdb", "perf record -g --", "rr record")
"""Offered after the operator's own recent prefixes."""


class TerminalQuestion(ConfirmScreen):
    """Whether to (re)start a node with a terminal to type into. The answer holds the keys
    typed after it (`hold`) from the moment it is given, before the answer's callback runs
    (later, as the dialog goes): the rest of a burst (`i y hello`) is the node's, and must
    not reach tuilaunch's own keys (`s` stops a node) while it restarts, nor after a no."""

    def __init__(self, question: str, yes: str) -> None:
        super().__init__(question, yes)
        self.hold = KeyHold()

    def dismiss(self, result: Any = None) -> Any:
        self.hold = hold_keys(self.app)
        return super().dismiss(result)


class TypingLine(Static, can_focus=True):
    """Holds the focus while the operator types into a node: every key goes to `send` (as
    Textual names it and its character), none to tuilaunch's own keys."""

    DEFAULT_CSS = """
    TypingLine { height: 1; padding: 0 1; background: $warning 40%; color: $text;
                 text-style: bold; }
    """
    # what the footer offers while typing (the app's own keys are hidden meanwhile); the
    # key itself reaches `on_key` like any other, which gives the keys back
    BINDINGS = [Binding("ctrl+right_square_bracket", "give_back", "Give the keys back",
                        key_display="ctrl+]")]

    def __init__(self, send: Callable[[str, str | None], None], id: str | None = None) -> None:
        super().__init__("", id=id)
        self.send = send

    def on_key(self, event: events.Key) -> None:
        event.stop()
        event.prevent_default()
        self.send(event.key, event.character)

    def on_paste(self, event: events.Paste) -> None:
        event.stop()
        self.send("paste", event.text)

    def action_give_back(self) -> None:
        self.send("ctrl+right_square_bracket", None)


class PrefixPrompt(ModalScreen[str | None]):
    """Which tool to restart a node under: typed, or one of the recent ones (up/down picks,
    enter runs, esc cancels)."""

    DEFAULT_CSS = dialog_css("PrefixPrompt", 80,
                             more="PrefixPrompt OptionList { height: auto; max-height: 8; }")
    BINDINGS = [Binding("escape", "cancel", "Cancel")]

    def __init__(self, process: str, recent: list[str]) -> None:
        super().__init__()
        self.process = process
        self.choices = list(dict.fromkeys([*recent, *KNOWN_PREFIXES]))

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static(Text(f"Restart {self.process} under (its next plain restart drops "
                              "it; type into it with i):"))
            yield Input(self.choices[0] if self.choices else "", id="prefix",
                        suggester=SuggestFromList(self.choices, case_sensitive=False))
            yield OptionList(*self.choices, id="recent")

    def on_mount(self) -> None:
        self.query_one(Input).focus()

    @on(Input.Submitted)
    def _submitted(self, event: Input.Submitted) -> None:
        self.dismiss(event.value.strip() or None)

    @on(OptionList.OptionSelected)
    def _picked(self, event: OptionList.OptionSelected) -> None:
        self.dismiss(str(event.option.prompt))

    def action_cancel(self) -> None:
        self.dismiss(None)


class CommandScreen(ModalScreen[None]):
    """A node's command line as it was started, ready to paste into a shell; y copies it."""

    DEFAULT_CSS = dialog_css("CommandScreen", 100)
    BINDINGS = [Binding("y", "copy", "Copy"), Binding("escape,q,c", "dismiss", "Close")]

    def __init__(self, process: str, line: str) -> None:
        super().__init__()
        self.process = process
        self.line = line

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Static(Text(f"{self.process} was started with (y copies it, esc "
                              "closes):", style="bold"))
            yield Static(Text(self.line), id="command-line")

    def action_copy(self) -> None:
        self.app.copy_to_clipboard(self.line)
        self.app.notify(f"copied the command line of {self.process}")
        self.dismiss(None)
