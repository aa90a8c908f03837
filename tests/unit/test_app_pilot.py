"""The TUI's rules under Pilot, over an in-memory session (memory_port.py): what a key does
on each kind of row, what a question starts on, what the status line says. No process, no
socket, no DDS: the session's events are told by the test, its commands read back.

The same rules are tested on the path users run (a session server, a real terminal, keys
in one burst) in tests/integration; here they are checked in milliseconds, each alone.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from textual.pilot import Pilot
from textual.widgets import Static
from textual.widgets._footer import FooterKey

from tests.unit.memory_port import MemoryPort
from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.events import ExitCause, Output, ProcessExited, Started, Stopping
from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.tree_panel import LaunchTree

BRINGUP = Path(__file__).resolve().parents[2] / "examples" / "bringup.py"
DEADLINE = 30.0
"""Seconds a condition has to hold: generous, as a loaded CI machine (2 cores, xdist) may
draw a frame a second or more late; a test that passes waits far less."""
POLL = 0.02
"""Seconds between two looks at a condition."""
PANE_FPS = 20.0
"""The output pane's repaint rate under test: users get session_link.PANE_FPS (1 a second,
for ssh), which would make each wait for a line on screen last up to a second; the rate
changes when the pane repaints, never what it shows once repainted."""


async def until(pilot: Pilot[int], check: Callable[[], object], what: str) -> None:
    """Waits (letting the app run between looks) until `check` holds; fails naming `what`
    once DEADLINE seconds of the wall clock have passed (not a count of pauses, which a
    loaded machine stretches)."""
    deadline = time.monotonic() + DEADLINE
    while not check():
        if time.monotonic() > deadline:
            raise AssertionError(f"not seen within {DEADLINE} s: {what}")
        # a plain sleep lets the app run as a user's terminal would: Pilot.pause(delay)
        # would post a message to each of the screen's ~200 widgets and wait for them all
        # at every look (~8 ms of CPU when nothing changes, doubling a poll's time under
        # load). The condition is what the test waits for; no barrier is needed to see it.
        await asyncio.sleep(POLL)


@asynccontextmanager
async def following(tmp_path: Path, launch: Path = BRINGUP,
                    arguments: dict[str, str] | None = None, *, started: bool = True,
                    size: tuple[int, int] = (80, 24), host: str | None = None,
                    name: str = "bringup", read_only: bool = False) -> AsyncIterator[
        tuple[TuiLaunchApp, Pilot[int], MemoryPort]]:
    """The TUI following an in-memory session of `launch`, as a client attaching to it:
    every enabled process already started (`started`; the session's history, replayed)
    or every one still waiting. `host`: the session is on that machine, over a link."""
    session = Session(str(launch), dict(arguments or {}))
    port = MemoryPort(session.plan, name=name, host=host)
    port.session = session
    enabled = session.plan.enabled_processes()
    if started:
        port.happened(*(Started(p.id, pid=1000 + n) for n, p in enumerate(enabled)))
    app = TuiLaunchApp(session, tmp_path, session_name=name, port=port, session_host=host,
                       read_only=read_only, pane_fps=PANE_FPS)
    record_toasts(app)
    async with app.run_test(size=size) as pilot:
        await until(pilot, lambda: app.supervisor is port and (
            not started or not enabled or
            app.launch_tree.states.get(enabled[-1].id) == "running"),
            "the session followed, its rows drawn")
        yield app, pilot, port
        port.detached = True  # the test is over: no "stopped elsewhere" pause
        port.end(0)


@asynccontextmanager
async def running(tmp_path: Path, **arguments: str) -> AsyncIterator[
        tuple[TuiLaunchApp, Pilot[int], MemoryPort]]:
    """The TUI over an in-memory session of examples/bringup.py, every enabled process
    started as its server says it live, at 80x24."""
    async with following(tmp_path, arguments=arguments, started=False) as (app, pilot, port):
        enabled = app.session.plan.enabled_processes()
        for number, proc in enumerate(enabled):
            port.tell(Started(proc.id, pid=1000 + number))
        await until(pilot, lambda: app.launch_tree.states.get(enabled[-1].id) == "running",
                    "every row running")
        yield app, pilot, port


def select(app: TuiLaunchApp, row: str) -> None:
    """Moves the tree's cursor to a process's row, or to the first row whose label
    starts with `row`, after its icon if it has one (a group: `ns /r1`, `all nodes`; an
    action: `call /r1/reset`)."""
    tree: LaunchTree = app.launch_tree
    if row in tree.rows:
        tree.move_cursor(tree.rows[row])
        return
    node = next(n for n in _walk(tree.root)
                if any(label.startswith(row) for label in (str(n.label), str(n.label)[2:])))
    tree.move_cursor(node)


def _walk(node):  # type: ignore[no-untyped-def]
    yield node
    for child in node.children:
        yield from _walk(child)


# --- what is on screen ----------------------------------------------------------------------

def status(app: TuiLaunchApp) -> str:
    """The status line, as drawn."""
    return str(app.status_bar.render())


def detail(app: TuiLaunchApp) -> str:
    """The line above the tree that says the selected row in full."""
    return str(app.detail_bar.render())


def row(app: TuiLaunchApp, process: str) -> str:
    """A process's row of the tree, as drawn."""
    return str(app.launch_tree.rows[process].label)


def pane(app: TuiLaunchApp) -> list[str]:
    """The lines the output pane shows (its filters applied), in full."""
    return app.output_panel.pane_lines()


def pane_status(app: TuiLaunchApp) -> str:
    """The output pane's own status line."""
    return str(app.output_panel.query_one("#output-status", Static).render())


def footer(app: TuiLaunchApp) -> dict[str, bool]:
    """The keys the footer offers, by description: True where it can be pressed, False
    where it is greyed out."""
    return {key.description: not key.has_class("-disabled")
            for key in app.screen.query(FooterKey)}


def toasts(app: TuiLaunchApp) -> list[str]:
    """Every notification the app has shown, oldest first, including those whose time on
    screen is over: a loaded machine may run the test's next look after a toast's seconds
    (the harnesses record them: `record_toasts`)."""
    return list(getattr(app, "said_toasts", None) or
                [str(n.message) for n in app._notifications])


def record_toasts(app: TuiLaunchApp) -> None:
    """From now on each notification's words are kept in `app.said_toasts`."""
    said: list[str] = []
    notify = app.notify

    def recorded(message: str, *args: Any, **options: Any) -> None:
        said.append(str(message))
        notify(message, *args, **options)

    app.notify = recorded  # type: ignore[method-assign]
    app.said_toasts = said  # type: ignore[attr-defined]


async def test_the_tree_shows_the_sessions_states(tmp_path: Path) -> None:
    async with running(tmp_path, robot="r2") as (app, pilot, port):
        assert app.launch_tree.states["talker-1"] == "running"
        port.tell(ProcessExited("talker-1", code=-11, reason="killed by SIGSEGV",
                                cause=ExitCause.CRASHED))
        await until(pilot, lambda: app.launch_tree.states.get("talker-1") == "failed",
                    "talker-1's row failed")
        await until(pilot, lambda: "1 failed" in str(app.status_bar.render()),
                    "the status line counting the failure")


async def test_s_on_a_node_stops_it_and_the_row_says_stopping(tmp_path: Path) -> None:
    async with running(tmp_path) as (app, pilot, port):
        select(app, "talker-1")
        await pilot.press("s")
        await until(pilot, lambda: ("stop", {"process": "talker-1"}) in port.asked,
                    "a stop of talker-1 asked of the session")
        assert [op for op in port.ops() if op in ("stop", "restart", "start")] == ["stop"]
        port.tell(Stopping("talker-1"))
        await until(pilot, lambda: app.launch_tree.states.get("talker-1") == "stopping",
                    "the row stopping")


async def test_a_pane_shows_the_lines_the_session_sends(tmp_path: Path) -> None:
    async with running(tmp_path) as (app, pilot, port):
        select(app, "talker-1")
        port.tell(Output("talker-1", stream="stdout", lines=["hello from the talker"]))
        await until(pilot, lambda: any("hello from the talker" in text for text in
                                       app.store.text(View(process="talker-1"))),
                    "the line in talker-1's pane")
