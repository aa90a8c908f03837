"""A browser tab's TUI started ahead of its tab (`tuilaunch serve`'s warm process).

Opening a served page used to wait for a whole Python start: the interpreter, then Textual,
the TUI and the client (about 1.3 s of a tab's first 2 to 4 s on a busy machine), before
the TUI even asked the session for its tree. serve_web.py keeps one process of this module
started ahead: it has imported all of that and waits on stdin for one line, the tab's
`attach` words and its size as JSON (`[["attach", "base"], 80, 24]`); then it is that
tab's `tuilaunch attach ...`, as textual-serve would have started it (the web driver named
in its environment). Nothing is connected before the line: a waiting process is no client
of any session, and sees nothing.

The line is read byte by byte straight from the descriptor, so the packets after it are
left whole for the web driver's reader.
"""

from __future__ import annotations

import json
import os
import sys
from typing import Any


def _warm() -> None:
    """What a tab's attach imports (python -X importtime), loaded while no tab waits."""
    import rich._emoji_codes  # noqa: F401
    import textual.drivers.web_driver
    import textual.layouts.factory
    import textual.layouts.horizontal
    import textual.layouts.stream
    import textual.scrollbar  # noqa: F401

    from ..tui import app  # noqa: F401
    from ..tui.fleet import app as fleet_app  # noqa: F401
    from . import commands, dispatch, fleet  # noqa: F401


def compact_footers() -> None:
    """In a browser every footer is Textual's compact one (no blank around each key): at
    1024x768, a tablet's 113 columns, the Nodes view's keys then fit where Restart and
    Start were cut off, so a tap reaches them. Only this process (a browser's tab) does it:
    a terminal's footer is unchanged."""
    from textual.widgets import Footer

    made = Footer.__init__
    # the palette's key is docked at the right end: the gap after each key, after it,
    # showed the last column of the keys scrolled under it ("^p palettet")
    Footer.DEFAULT_CSS += "Footer.-compact FooterKey.-command-palette { margin-right: 0; }\n"

    def compact_init(self: Footer, *args: Any, **kwargs: Any) -> None:
        kwargs["compact"] = True
        made(self, *args, **kwargs)

    Footer.__init__ = compact_init  # type: ignore[method-assign]


PHONE = 70
"""Columns below which a browser's footer is a phone's (390 px wide: about 42 columns)."""
PHONE_FIRST = ("Stop", "Restart", "Start", "Type", "Search")
"""What an operator taps most, first in a phone's footer (the palette, ^p at its right
end, reaches every other key)."""
PHONE_CSS = """
Footer.-phone { layout: grid; grid-columns: auto; grid-rows: 1; height: 2; }
"""


def phone_footers() -> None:
    """In a browser narrower than PHONE columns the footer is two rows of three keys, the
    node's keys first (PHONE_FIRST): in one row, a phone showed Search, Level, Filter and
    half of Type, and no Stop, Restart or Start to tap. Wider, as it was."""
    from textual import events
    from textual.app import ComposeResult
    from textual.widget import Widget
    from textual.widgets import Footer
    from textual.widgets._footer import FooterKey

    composed = Footer.compose

    def rank(widget: Widget) -> int:
        description = widget.description if isinstance(widget, FooterKey) else ""
        return PHONE_FIRST.index(description) if description in PHONE_FIRST else \
            len(PHONE_FIRST)

    def phone_compose(self: Footer) -> ComposeResult:
        widgets = list(composed(self))
        phone = self.app.size.width < PHONE
        self.set_class(phone, "-phone")
        if phone:
            widgets.sort(key=rank)  # stable: the others keep their order
            self.styles.grid_size_columns = 3  # compose set one column per key
        yield from widgets

    def on_resize(self: Footer, event: events.Resize) -> None:
        if (self.app.size.width < PHONE) != self.has_class("-phone"):
            self.call_after_refresh(self.recompose)

    Footer.compose = phone_compose  # type: ignore[method-assign]
    Footer.on_resize = on_resize  # type: ignore[attr-defined]
    Footer.DEFAULT_CSS += PHONE_CSS


def _go_line() -> bytes:
    line = bytearray()
    while not line.endswith(b"\n"):
        byte = os.read(0, 1)
        if not byte:  # serve went away before a tab came: nothing to do
            raise SystemExit(0)
        line += byte
    return bytes(line)


def name_process(name: bytes) -> None:
    """The name ps and /proc/PID/comm show (a waiting process is no tab yet: tests and
    an operator's ps tell them apart)."""
    try:
        import ctypes

        ctypes.CDLL(None).prctl(PR_SET_NAME, ctypes.c_char_p(name[:15]), 0, 0, 0)
    except (OSError, AttributeError):
        pass  # not Linux: the name is only a help


PR_SET_NAME = 15
WAITING, TAB = b"tuilaunch-warm", b"tuilaunch-tab"


def main() -> int:
    name_process(WAITING)
    _warm()
    try:
        words, width, height = json.loads(_go_line())
        words = [str(w) for w in words]
        os.environ["COLUMNS"], os.environ["ROWS"] = str(int(width)), str(int(height))
        name_process(TAB)
    except (ValueError, TypeError):
        print("tuilaunch serve: a warm tab got no attach line", file=sys.stderr)
        return 2
    compact_footers()
    phone_footers()
    from .dispatch import main as tuilaunch_main

    return tuilaunch_main(words)


if __name__ == "__main__":
    raise SystemExit(main())
