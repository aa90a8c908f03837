"""The Pilot tests' one change to Textual: a footer key starts as its footer draws it.

Textual's FooterKey starts compact and is then bound to its Footer's `compact` (False in
tuilaunch's footers), so each key of every footer redrawn (a focus move, a tab shown) has
its styles worked out twice, once for each class change: a third of the CPU a Pilot test
spends, as the Footer is redrawn after most keys. Starting each key non-compact, as those
footers draw it, draws the same footer (the binding still sets a compact footer's keys)
without the two restyles. tuilaunch could do the same in its own footer, for its users.
"""

from __future__ import annotations

from typing import Any

from textual.widgets._footer import FooterKey

_made = FooterKey.__init__


def _made_as_footer_draws(key: FooterKey, *args: Any, **kwargs: Any) -> None:
    _made(key, *args, **kwargs)
    key.set_reactive(FooterKey.compact, False)


FooterKey.__init__ = _made_as_footer_draws  # type: ignore[method-assign]
