"""Toasts said once: a message already on screen is not stacked again.

A failing command over a group (four nodes whose machine is unreachable), a key pressed
again while its refusal shows, a link that drops and drops again, each said the same line:
four identical toasts hid a quarter of the screen and said nothing more than one.
"""

from __future__ import annotations

import time
from typing import Any

from textual.app import App
from textual.notifications import SeverityLevel


class OnceToasts(App[Any]):
    """`notify` that shows a message once while an identical one (same text, title and
    severity) is still on screen."""

    def __init__(self, *args: Any, **options: Any) -> None:
        super().__init__(*args, **options)
        self._toasts_until: dict[tuple[str, str, str], float] = {}
        """Each message shown, and until when (monotonic) its toast is on screen."""

    def notify(self, message: str, *, title: str = "",
               severity: SeverityLevel = "information", timeout: float | None = None,
               markup: bool = True) -> None:
        shown_for = self.NOTIFICATION_TIMEOUT if timeout is None else timeout
        now = time.monotonic()
        said = (str(message), title, severity)
        if self._toasts_until.get(said, 0.0) > now:
            return  # still on screen: a second one says nothing more
        self._toasts_until = {k: t for k, t in self._toasts_until.items() if t > now}
        self._toasts_until[said] = now + shown_for
        super().notify(message, title=title, severity=severity, timeout=timeout,
                       markup=markup)
