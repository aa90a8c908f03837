"""Every private Textual internal tuilaunch relies on, in one place, each with why.

Textual has no public hook for what key_order.py does (keys handled one at a time, each
where the focus is once the one before it is done) nor for a few key details of the
fields: those reach into Textual's underscore names. They are used through this module
only, and `INTERNALS` lists each one with the shape relied on, so that
tests/unit/test_textual_compat.py fails on the Textual upgrade that removes or reshapes
one, naming it, instead of keys going astray in a running TUI. Written against Textual
8.2; a name overridden in a subclass elsewhere (a private handler) is listed here too.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from textual import events
from textual._context import active_message_pump as active_message_pump
from textual.app import ComposeResult
from textual.binding import Binding
from textual.keys import _character_to_key, _get_unicode_name_from_key
from textual.message import Message
from textual.message_pump import MessagePump
from textual.widget import Widget
from textual.widgets import Footer as TextualFooter
from textual.widgets._footer import FooterKey


@dataclass(frozen=True)
class Internal:
    """One private name: where it lives, what is relied on, and why."""

    where: str
    """`module:Name.attribute`, or `module:name` for a module-level name."""
    shape: str
    """"call(param, ...)": a callable with these parameters (self included for a method);
    "attribute": set on every instance (checked on a fresh one); "value": a module name."""
    why: str


INTERNALS: tuple[Internal, ...] = (
    Internal("textual._context:active_message_pump", "value",
             "the widget, screen or app handling the current message: a key's trip ends "
             "after the handler that stopped it returns (key_order.TrackedKey.stop)"),
    Internal("textual._xterm_parser:XTermParser._sequence_to_key_events",
             "call(self, sequence, alt)",
             "wrapped so ESC and a punctuation key in one read stay two keys "
             "(key_order.keep_escape_before_punctuation)"),
    Internal("textual.keys:_character_to_key", "call(character)",
             "the key name of a character: the key typed after ESC, split from an alt-key"),
    Internal("textual.keys:_get_unicode_name_from_key", "call(key)",
             "a key's character, so the footer leaves out the keys a field types "
             "(screens/fields.py)"),
    Internal("textual.events:Key._bubble_to", "call(self, widget)",
             "overridden to know whose queue a key is in (a widget removed with it never "
             "hands it on: key_order.lost)"),
    Internal("textual.message:Message._set_forwarded", "call(self)",
             "overridden to know the widget a key was forwarded to"),
    Internal("textual.message:Message._sender", "attribute",
             "cleared on the app's own keys: a key sent by the app stops at the screen, "
             "before the app's bindings ran"),
    Internal("textual.message_pump:MessagePump._message_queue", "attribute",
             "which widgets still have messages to process before the next key goes out "
             "(key_order.settle)"),
    Internal("textual.message_pump:MessagePump._closing", "attribute",
             "a widget closing never processes the key in its queue"),
    Internal("textual.message_pump:MessagePump._closed", "attribute",
             "a widget closed never processes the key in its queue"),
    Internal("textual.dom:DOMNode._bindings", "attribute",
             "a field's own bindings (`key_to_bindings`), run before typing a key it does not "
             "type (screens/fields.py)"),
    Internal("textual.widgets._input:Input._on_key", "call(self, event)",
             "overridden by the fields (screens/fields.py, dialogs.py) to keep keys in order "
             "and leave on escape and enter"),
    Internal("textual.widgets._footer:FooterKey", "value",
             "the footer's keys, made as the footer draws them (`Footer`): Textual makes "
             "each compact, then binds it to its footer's `compact`, restyling every key "
             "twice on each redraw of the footer (after most keys)"),
    Internal("textual.widgets._footer:FooterKey._disabled", "attribute",
             "whether a footer key is greyed (its press rings the bell instead): set with "
             "its `-disabled` class, a key drawn is greyed or offered where it is, the "
             "footer not drawn anew (`Footer`)"),
    Internal("textual.widgets._tabbed_content:TabbedContent._on_tab_pane_focused",
             "call(self, event)",
             "overridden (app.py): a late focus message must not flip the tab back"),
)


def resolve(internal: Internal) -> Any:
    """The object an Internal names (AttributeError/ImportError when it is gone)."""
    import importlib

    module_name, _, path = internal.where.partition(":")
    target: Any = importlib.import_module(module_name)
    owner_path, _, attribute = path.rpartition(".")
    for part in filter(None, owner_path.split(".")):
        target = getattr(target, part)
    if internal.shape == "attribute":
        return target, attribute  # an instance attribute: checked on an instance
    return getattr(target, attribute)


def parameters(function: Callable[..., Any]) -> list[str]:
    return list(inspect.signature(function).parameters)


# --- the uses ------------------------------------------------------------------------------

def character_to_key(character: str) -> str:
    return _character_to_key(character)


def unicode_name_of_key(key: str) -> str:
    return _get_unicode_name_from_key(key)


def xterm_parser() -> Any:
    """Textual's terminal parser class (imported when a TUI starts, as Textual does)."""
    from textual._xterm_parser import XTermParser

    return XTermParser


def has_messages(pump: MessagePump) -> bool:
    return not pump._message_queue.empty()


def is_closing(pump: MessagePump) -> bool:
    return bool(pump._closing or pump._closed)


def send_as_app(message: Message) -> None:
    """No sender: the message goes the whole way, as a key read from the terminal does."""
    message._sender = None


def own_bindings(widget: Widget, key: str) -> Iterable[Binding]:
    """The bindings a widget itself declares for `key` (not its ancestors')."""
    return widget._bindings.key_to_bindings.get(key, ())


class TripKey(events.Key):
    """A key that is told where it goes: `went_to` when it bubbles to a widget,
    `forwarded` when the app forwards it to the focused widget."""

    def went_to(self, widget: MessagePump) -> None:
        """Called as the key bubbles to `widget` (whose queue it is now in)."""

    def forwarded(self) -> None:
        """Called once the app has forwarded the key."""

    def _bubble_to(self, widget: MessagePump) -> None:
        self.went_to(widget)
        super()._bubble_to(widget)

    def _set_forwarded(self) -> None:
        super()._set_forwarded()
        self.forwarded()


class Footer(TextualFooter):
    """Textual's footer, its keys made as it draws them. Textual makes each FooterKey
    compact, then binds it to the footer's `compact` (False in a terminal): every key of
    the footer was restyled twice each time the footer is drawn anew, which is after most
    keys (a focus move, a tab shown): a third of the CPU a keypress cost. Each bound key
    starts with its footer's value instead; the binding still follows a change of it.

    And it is drawn anew only when the keys it shows changed; when only whether some can
    be pressed changed (a node's row selected offers Type and Debug, a node that ended
    greys Stop), those are greyed or offered where they are. Textual redraws it at every
    `refresh_bindings`, removing each FooterKey before mounting the new ones, the page
    still showing the old ones meanwhile; a FooterKey acts on the press, and a press that
    came in between went to a key already removed: no key (a tap on Stop right after a
    tap on a row, lost in a browser under load)."""

    _drawn: tuple[object, ...] | None = None
    """What the footer's keys were drawn from (`_keys`), when last composed."""

    def _keys(self, screen: Any) -> tuple[object, ...]:
        """Everything compose draws the keys from: each shown binding, whether it is
        enabled, its tooltip; the palette's key is among the active bindings too."""
        return tuple((binding.key, binding.description, binding.action, binding.show,
                      binding.group, enabled, tooltip)
                     for (_, binding, enabled, tooltip) in screen.active_bindings.values()
                     if binding.show or binding.action == "command_palette")

    def bindings_changed(self, screen: Any) -> None:
        if self._drawn is not None and screen is self.screen and self.is_attached:
            keys = self._keys(screen)
            if keys == self._drawn:
                return  # a redraw would draw the same keys
            if self._enable_in_place(keys):
                self._drawn = keys
                return
        super().bindings_changed(screen)

    def _enable_in_place(self, keys: tuple[Any, ...]) -> bool:
        """The keys drawn greyed or offered as `keys` says, when they are the same keys
        and only that changed: True then; False when the footer must be drawn anew."""
        def but_enabled(drawn: tuple[Any, ...]) -> list[tuple[Any, ...]]:
            return [key[:5] + key[6:] for key in drawn]

        if but_enabled(keys) != but_enabled(self._drawn or ()):
            return False
        enabled = {key[0]: bool(key[5]) for key in keys}
        widgets = list(self.query(FooterKey))
        if any(widget.key not in enabled for widget in widgets):
            return False
        for widget in widgets:
            if widget._disabled == enabled[widget.key]:
                widget._disabled = not enabled[widget.key]
                widget.set_class(widget._disabled, "-disabled")
        return True

    def compose(self) -> ComposeResult:
        if self._bindings_ready:
            self._drawn = self._keys(self.screen)
        for widget in super().compose():
            # the palette's key is not bound to the footer: it stays compact, as Textual
            # draws it
            if isinstance(widget, FooterKey) and not widget.has_class("-command-palette"):
                widget.set_reactive(FooterKey.compact, self.compact)
            yield widget
