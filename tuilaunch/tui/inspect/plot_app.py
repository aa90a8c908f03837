"""`tuilaunch plot NAME TOPIC FIELD ...` without --csv: the plot screen of the TUI
(screens/plot_screen.py), full screen in a terminal of its own, `q` leaves.

It reaches each session as the TUI does, through its port (client/remote_supervisor.py,
on an engine thread of its own): the screen asks its streams of them (`SessionPlots`), and
each session's `plot` readings are handed to it. A session that ends, or an ssh link that
drops, ends the plot with the line the other streaming commands say (`error` keeps it for
the command line: a LinkLost, status 1; a SessionError, status 2).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Awaitable
from functools import partial
from pathlib import Path
from typing import Any, TypeVar

from textual.app import App

from ...client.inspect.plot_series import Source
from ...client.link import LinkLost, parse_session
from ...client.port import LaunchPort
from ...engine.errors import LaunchError
from ...engine.run.engine_thread import EngineThread
from ...engine.run.events import Event, PlotSamples
from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.request import Request
from ..screens.plot_screen import PlotScreen, SessionPlots

R = TypeVar("R")

DRAIN_S = 0.1
"""Seconds between handing the readings received to the screen."""


class PlotApp(App[int]):
    """One plot, full screen, of the sessions in `ports` (by the name the user gave)."""

    ENABLE_COMMAND_PALETTE = False  # the footer's room is the plot's keys'

    def __init__(self, engine: EngineThread, ports: dict[str, LaunchPort],
                 sources: list[Source], stamp: bool, duration: float | None,
                 runs: dict[str, Any]) -> None:
        """`runs`: each port's `run()` future (its end is the session's, or its link's)."""
        super().__init__()
        self.engine = engine
        self.ports = ports
        self.runs = runs
        self.duration = duration
        self.error: LaunchError | None = None
        self.readings: deque[dict[str, Any]] = deque()
        requesters = {label: partial(self._request, port) for label, port in ports.items()}
        self.plot_screen = PlotScreen(SessionPlots(requesters, self._leave), sources, stamp,
                                      started=True, folder=Path.cwd())
        for port in ports.values():
            port.subscribe(self._take)

    def _take(self, event: Event) -> None:
        """On the engine thread: a reading kept for the screen's next drain."""
        if isinstance(event, PlotSamples):
            self.readings.append(event.data or {})

    def _request(self, port: LaunchPort, request: Request[R]) -> Awaitable[R]:
        return self.engine.run(port.request(request))

    def on_mount(self) -> None:
        self.push_screen(self.plot_screen)
        self.set_interval(DRAIN_S, self._drain)
        if self.duration is not None:
            self.set_timer(self.duration, self._leave)

    def _drain(self) -> None:
        while self.readings:
            self.plot_screen.add(self.readings.popleft())
        if self.error is None:
            self.error = self._gone()
            if self.error is not None:
                self._leave()

    def _gone(self) -> LaunchError | None:
        """Why the plot cannot go on: a link lost, a session ended; None while all run."""
        for label, port in self.ports.items():
            lost = port.link_lost
            if lost is not None:  # said as hz and echo say it: the session may run on
                host = parse_session(label).host or label
                return LinkLost(f"link to {host} lost: {port.lost_reason or 'closed'}")
            if self.runs[label].done():
                return SessionError(f"session {label} ended")
        return None

    def _leave(self) -> None:
        self.exit(0 if self.error is None else 1)


def run_plot_app(engine: EngineThread, ports: dict[str, LaunchPort], sources: list[Source],
                 stamp: bool, duration: float | None, runs: dict[str, Any]) -> None:
    """The plot until `q`, `duration` or its end; raises what ended it (LaunchError)."""
    app = PlotApp(engine, ports, sources, stamp, duration, runs)
    app.run()
    if app.error is not None:
        raise app.error


