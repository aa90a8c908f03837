"""`p` on a topic: the plot screen opened on its first numeric field, from the single TUI's
Topics tab and from a fleet session's alike (one path: what a topic without a numeric field
or a session's refusal says is written once)."""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from textual.app import App

from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.requests import PlotFields

Ask = Callable[[Any], Awaitable[Any]]
"""A session's request, answered (SessionError: the session's refusal, or no link)."""


async def open_plot(app: App[Any], ask: Ask, topic: str, requesters: Mapping[str, Ask],
                    label: str, leave: Callable[[], None], said: str = "") -> Any:
    """Pushes the plot of `topic` of the session `ask` reaches (`label` among `requesters`,
    the sessions the screen can add topics of), its first numeric field chosen (`f` picks
    others); returns the screen, to hand it the session's `plot` readings. None, said in
    one line starting with `said` (a fleet's session), when it has no numeric field or the
    session refuses."""
    try:
        info = await ask(PlotFields(topic=topic))
    except SessionError as exc:
        app.notify(f"{said}{str(exc).split(': ', 1)[-1]}", severity="error", title="plot")
        return None
    numeric = list(info.get("fields") or [])
    if not numeric:
        app.notify(f"{said}{topic} ({info.get('type')}) has no numeric field to plot",
                   severity="warning", title="plot")
        return None
    # plotext: imported only once a plot is shown
    from ...client.inspect.plot_series import Source
    from ..screens.plot_screen import PlotScreen, SessionPlots

    screen = PlotScreen(SessionPlots(dict(requesters), leave),
                        [Source(label, topic, numeric[:1])])
    app.push_screen(screen)
    return screen
