"""A text field that applies keys in the order they were typed.

Over ssh several keys often arrive in one read. Textual's Input inserts printable keys as
they reach it, but its editing keys (backspace, ctrl+u, ...) are bindings that run only after
the key has bubbled up to the app, so `ctrl+u 3` in one read could insert `3` first and then
erase it. Here the field runs its own bindings as the key arrives, before the next key.
Escape leaves the field at once, so the keys typed after it are not typed into it.
"""

from __future__ import annotations

from typing import Any

from textual import events
from textual.widgets import Input


class Field(Input):
    DEFAULT_CSS = """
    Field:focus { border: tall $accent; background-tint: $accent 12%; }
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        # a blinking cursor repaints the field twice a second for nothing: bytes over ssh
        self.cursor_blink = False

    async def _on_key(self, event: events.Key) -> None:
        if event.is_printable:
            await super()._on_key(event)
            return
        if event.key == "escape":
            event.stop()
            event.prevent_default()
            await self.run_action("app.leave_field")
            return
        for binding in self._bindings.key_to_bindings.get(event.key, ()):
            if self.check_action(binding.action, ()) is False:
                continue
            event.stop()
            event.prevent_default()
            await self.run_action(binding.action)
            return
        await super()._on_key(event)
