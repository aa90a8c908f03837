"""A text field that applies keys in the order they were typed.

Over ssh several keys often arrive in one read. Textual's Input inserts printable keys as
they reach it, but its editing keys (backspace, ctrl+u, ...) are bindings that run only after
the key has bubbled up to the app, so `ctrl+u 3` in one read could insert `3` first and then
erase it. Here the field runs its own bindings as the key arrives, before the next key.
Escape leaves the field at once (and enter, for a field that closes on submit; escape and a
key read together are split into the two by the app, key_order.py); keys that
reached the field after it lost the focus go back to the app, in order, for the widget that
has the focus now, instead of being typed into a field the user has left.
"""

from __future__ import annotations

import unicodedata
from typing import Any

from textual import events
from textual.widgets import Checkbox, Input

from ..key_order import reroute_key
from ..textual_compat import own_bindings, unicode_name_of_key


class Field(Input):
    DEFAULT_CSS = """
    Field:focus { border: tall $accent; background-tint: $accent 12%; }
    /* a compact field has no border: bold underlined text shows the focus, 8 colours too */
    Field.-textual-compact:focus { text-style: bold underline; }
    """

    def __init__(self, *args: Any, leave_on_enter: bool = False, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # a blinking cursor repaints the field twice a second for nothing: bytes over ssh
        self.cursor_blink = False
        self.leave_on_enter = leave_on_enter

    def check_consume_key(self, key: str, character: str | None) -> bool:
        """The footer leaves out the keys a field types: Textual knows no character for
        `slash`, `backslash`... and offered `/ Search` while the search field had the keys."""
        if character is None:
            character = {"slash": "/", "backslash": "\\"}.get(key)
        if character is None:
            try:
                character = unicodedata.lookup(unicode_name_of_key(key))
            except KeyError:
                pass
        return super().check_consume_key(key, character)

    async def _on_key(self, event: events.Key) -> None:
        if self.screen.focused is not self:
            event.stop()
            event.prevent_default()
            reroute_key(self.app, events.Key(event.key, event.character))
            return
        if event.key == "enter" and self.leave_on_enter:
            event.stop()
            event.prevent_default()
            await self.action_submit()
            await self.run_action("app.leave_field")
            return
        if event.key == "escape":
            event.stop()
            event.prevent_default()
            await self.run_action("app.leave_field")
            return
        if event.is_printable:
            await super()._on_key(event)
            return
        for binding in own_bindings(self, event.key):
            if self.check_action(binding.action, ()) is False:
                continue
            event.stop()
            event.prevent_default()
            await self.run_action(binding.action)
            return
        await super()._on_key(event)


class Toggle(Checkbox):
    """A checkbox that reads true or false without colour: `X` or blank in its box, and
    the box `[ ]` on a console whose font has no half blocks (TERM=linux)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        from .tree_panel import ascii_terminal

        super().__init__(*args, **kwargs)
        if ascii_terminal():
            self.BUTTON_LEFT, self.BUTTON_RIGHT = "[", "]"
        self.BUTTON_INNER = "X" if self.value else " "

    def watch_value(self) -> None:
        self.BUTTON_INNER = "X" if self.value else " "
        super().watch_value()
