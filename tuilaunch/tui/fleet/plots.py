"""`p` in a fleet view's Topics tab: the single TUI's plot screen (screens/plot_screen.py),
over the fleet's sessions.

The topic picked is plotted from the selected session, through its own link; the screen
reaches every session of the fleet by its label (`robot1:base`), so `a` there adds a topic
of another robot beside it. The sessions' `plot` readings are handed to the screen as they
come (each stream's tag says whose).
"""

from __future__ import annotations

from typing import Any

from textual.app import App

from ..inspect.plots import open_plot
from ..session_view import SessionView


class FleetPlots:
    """The plot on screen, if any, of `app`, over the sessions of `members`."""

    def __init__(self, app: App[Any], members: list[SessionView]) -> None:
        self.app, self.members = app, members
        self.screen: Any = None
        """The plot on screen (the screen's module is imported with the first plot)."""

    def open(self, member: SessionView, topic: str) -> None:
        self.app.run_worker(self._open(member, topic), group="plot", exit_on_error=False)

    def add(self, data: dict[str, Any]) -> None:
        """A `plot` reading of one of the sessions."""
        if self.screen is not None:
            self.screen.add(data)

    async def _open(self, member: SessionView, topic: str) -> None:
        requesters = {m.label: m.request for m in self.members}
        self.screen = await open_plot(self.app, member.request, topic,
                                      requesters, member.label, self._leave, f"{member.label}: ")

    def _leave(self) -> None:
        self.screen = None
        self.app.pop_screen()
