"""A text field that applies keys in the order they were typed.

Over ssh several keys often arrive in one read. Textual's Input inserts printable keys as
they reach it, but its editing keys (backspace, ctrl+u, ...) are bindings that run only after
the key has bubbled up to the app, so `ctrl+u 3` in one read could insert `3` first and then
erase it. Here the field runs its own bindings as the key arrives, before the next key.
Escape leaves the field at once (and enter, for a field that closes on submit); keys that
reached the field after it lost the focus go back to the app, in order, for the widget that
has the focus now, instead of being typed into a field the user has left.
"""

from __future__ import annotations

from typing import Any

from textual import events
from textual.keys import _character_to_key
from textual.widgets import Input

from ..key_order import reroute_key

# Textual reads ESC and a digit arriving in one read (esc then 3, typed fast over ssh or sent
# by tmux) as the character macOS's option key gives: in a field that is "leave, then 3"
ESC_DIGITS = {"¡": "1", "™": "2", "£": "3", "¢": "4", "∞": "5", "§": "6", "¶": "7",
              "•": "8", "ª": "9", "º": "0"}


def after_escape(event: events.Key) -> events.Key | None:
    """The key typed right after escape, when both came in one read: ESC and a digit read
    as the option-key character, ESC and another key as `alt+KEY` (no alt binding of ours
    or of Input's uses a printable key)."""
    character = event.character or ""
    if character in ESC_DIGITS:
        digit = ESC_DIGITS[character]
        return events.Key(digit, digit)
    if event.key.startswith("alt+") and len(character) == 1 and character.isprintable():
        return events.Key(_character_to_key(character), character)
    return None


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
        following = after_escape(event)
        if event.key == "escape" or following is not None:
            event.stop()
            event.prevent_default()
            await self.run_action("app.leave_field")
            if following is not None:
                reroute_key(self.app, following)
            return
        if event.is_printable:
            await super()._on_key(event)
            return
        for binding in self._bindings.key_to_bindings.get(event.key, ()):
            if self.check_action(binding.action, ()) is False:
                continue
            event.stop()
            event.prevent_default()
            await self.run_action(binding.action)
            return
        await super()._on_key(event)
