"""What the Pilot tests moved from tests/integration share: the TUI following an in-memory
session (memory_port.py) with the options `tuilaunch` takes (a scrollback, a terminal's
size), keys posted as one read from a terminal delivers them, and a wait until every key
typed has been handled (for what a key must not have done)."""

from __future__ import annotations

import textwrap
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from textual import events
from textual.pilot import Pilot
from textual.widgets import Static

from tests.unit.memory_port import MemoryPort
from tests.unit.test_app_pilot import BRINGUP, PANE_FPS, record_toasts, until
from tests.unit.test_app_pilot import toasts as toasts_said
from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.events import Started
from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.screens.line_view import LineView

CHARACTERS = {"slash": "/", "backslash": "\\", "colon": ":", "space": " "}


def launch_file(tmp_path: Path, text: str, name: str = "launch.py") -> Path:
    """A launch file written for the test (the session reads it in this process: nothing
    it names is run)."""
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


@asynccontextmanager
async def shown(tmp_path: Path, launch: Path = BRINGUP,
                arguments: dict[str, str] | None = None, *, size: tuple[int, int] = (80, 24),
                started: bool = True, name: str = "bringup", port: type[MemoryPort] = MemoryPort,
                **options: Any) -> AsyncIterator[tuple[TuiLaunchApp, Pilot[int], MemoryPort]]:
    """The TUI following an in-memory session of `launch`, as test_app_pilot.following, with
    the app's `options` (scrollback=...); every enabled process started (`started`)."""
    session = Session(str(launch), dict(arguments or {}))
    memory = port(session.plan, name=name)
    memory.session = session
    enabled = session.plan.enabled_processes()
    if started:
        memory.happened(*(Started(p.id, pid=1000 + n) for n, p in enumerate(enabled)))
    options.setdefault("pane_fps", PANE_FPS)
    app = TuiLaunchApp(session, tmp_path, session_name=name, port=memory, **options)
    record_toasts(app)
    async with app.run_test(size=size) as pilot:
        await until(pilot, lambda: app.supervisor is memory and (
            not started or not enabled or
            app.launch_tree.states.get(enabled[-1].id) == "running"),
            "the session followed, its rows drawn")
        yield app, pilot, memory
        memory.detached = True  # the test is over: no "stopped elsewhere" pause
        memory.end(0)


def burst(app: TuiLaunchApp, *keys: str) -> None:
    """Keys as one read from the terminal delivers them: posted together, nothing run in
    between (Pilot.press waits after each key, which hides ordering faults)."""
    for key in keys:
        char = key if len(key) == 1 else CHARACTERS.get(key)
        app.post_message(events.Key(key, char))


async def keys_handled(pilot: Pilot[int], app: TuiLaunchApp) -> None:
    """Returns once every key posted so far has been handled, and what each set in motion
    processed: for a test of what a key must not have done (no fixed wait)."""
    await pilot.pause()  # the keys posted are read: each handled or waiting its turn
    await until(pilot, lambda: app._key_in_flight is None and not app._keys_waiting
                and not app._key_holds, "every key typed handled")
    await pilot.pause()


async def burst_dropped(pilot: Pilot[int], app: TuiLaunchApp) -> None:
    """Returns once the burst being dropped is over (key_order.BURST_GAP without a key)."""
    await until(pilot, lambda: time.monotonic() >= app.dropping_until, "the burst over")
    await pilot.pause()


def dialogs(app: TuiLaunchApp) -> list[str]:
    """The screens over the main one, by kind."""
    return [type(screen).__name__ for screen in app.screen_stack[1:]]


def toasts(app: TuiLaunchApp) -> list[str]:
    return toasts_said(app)


def line_view(app: TuiLaunchApp) -> LineView:
    return app.output_panel.line_view


def rows(app: TuiLaunchApp) -> list[str]:
    """The pane's rows as the user reads them, to the last one written."""
    shown_rows = line_view(app).visible_text()
    while shown_rows and not shown_rows[-1]:
        shown_rows.pop()
    return shown_rows


def pane_status(app: TuiLaunchApp) -> str:
    return str(app.output_panel.query_one("#output-status", Static).render())
