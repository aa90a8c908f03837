"""`tuilaunch plot NAME TOPIC FIELD ...` without --csv: the plot screen of the TUI
(screens/plot_screen.py), full screen in a terminal of its own, `q` leaves.

It reads the session's link (a blocking one, client/link.py) on a thread of its own and
hands each `plot` event to the screen; a change of fields is sent on the same link, its
reply read by the thread among the events.
"""

from __future__ import annotations

import threading
import time
from typing import Any

from textual.app import App

from ..client.link import Link
from .screens.plot_screen import PlotScreen

READ_SLICE = 0.2
"""Seconds the reading thread waits at a time before it looks whether the app has ended."""


class PlotApp(App[int]):
    """One plot, full screen."""

    def __init__(self, link: Link, answer: dict[str, Any], duration: float | None) -> None:
        super().__init__()
        self.link = link
        self.answer = answer
        self.duration = duration
        self.ended = threading.Event()
        self.error: str | None = None
        self.plot_screen = PlotScreen(
            str(answer["topic"]), str(answer["type"]), list(answer["numeric"]),
            list(answer["fields"]), self._ask, self._leave)

    def on_mount(self) -> None:
        self.push_screen(self.plot_screen)
        threading.Thread(target=self._read, daemon=True, name="plot link").start()
        if self.duration is not None:
            self.set_timer(self.duration, self._leave)

    def _ask(self, fields: list[str], tag: int) -> None:
        self.link.send("plot", topic=self.answer["topic"], fields=fields, tag=tag)

    def _leave(self) -> None:
        self.ended.set()
        self.exit(0 if self.error is None else 1)

    def _read(self) -> None:
        """Until the app ends or the session does: events to the screen, refusals said."""
        while not self.ended.is_set():
            try:
                message = self.link.receive_until(time.monotonic() + READ_SLICE)
            except TimeoutError:
                continue
            except (OSError, ValueError):
                message = None
            if message is None or message.get("type") == "ended":
                if not self.ended.is_set():
                    self.error = f"session {self.link.name} ended"
                    self.call_from_thread(self._leave)
                return
            if message.get("type") == "reply" and not message.get("ok"):
                self.call_from_thread(self.notify, str(message.get("error")),
                                      severity="error", title="plot")
            for event in message.get("events") or []:
                if event.get("kind") == "plot":
                    self.call_from_thread(self.plot_screen.add, event.get("data") or {})


def run_plot_app(link: Link, answer: dict[str, Any], duration: float | None) -> int:
    app = PlotApp(link, answer, duration)
    status = app.run()
    if app.error is not None:
        print(f"tuilaunch plot: {app.error}")
    return int(status or 0)
