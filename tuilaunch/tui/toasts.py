"""Toasts said once: a message already on screen is not stacked again.

A failing command over a group (four nodes whose machine is unreachable), a key pressed
again while its refusal shows, a link that drops and drops again, each said the same line:
four identical toasts hid a quarter of the screen and said nothing more than one.
"""

from __future__ import annotations

import time

from textual.notifications import SeverityLevel


class OnceToasts:
    """Which toasts to show: a message is shown once while an identical one (same text,
    title and severity) is still on screen. The single TUI and the fleet view each hold
    one, and their `notify` asks it first."""

    def __init__(self) -> None:
        self._toasts_until: dict[tuple[str, str, str], float] = {}
        """Each message shown, and until when (monotonic) its toast is on screen."""

    def new(self, message: str, title: str, severity: SeverityLevel, shown_for: float) -> bool:
        """Whether the toast says something not on screen now (it is noted as shown)."""
        now = time.monotonic()
        said = (str(message), title, severity)
        if self._toasts_until.get(said, 0.0) > now:
            return False  # still on screen: a second one says nothing more
        self._toasts_until = {k: t for k, t in self._toasts_until.items() if t > now}
        self._toasts_until[said] = now + shown_for
        return True
