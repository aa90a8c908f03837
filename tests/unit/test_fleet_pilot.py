"""The fleet view's rules under Pilot, over two in-memory sessions (memory_port.py): the
single TUI's rules hold on each session of a fleet (a group's stop asks, naming the
session; `i` on a group drops its burst; a lost link is said on its own root only), and a
key acts on the focused session alone."""

from __future__ import annotations

import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from textual import events
from textual.pilot import Pilot

from tests.unit.memory_port import MemoryPort
from tests.unit.test_app_pilot import BRINGUP, until
from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.events import Started
from tuilaunch.tui.fleet.app import FleetApp
from tuilaunch.tui.screens.dialogs import ConfirmScreen


@asynccontextmanager
async def fleet() -> AsyncIterator[tuple[FleetApp, Pilot[int], list[MemoryPort]]]:
    """A fleet view of two sessions of examples/bringup.py, `one` and `two`, on robot1 and
    robot2, every enabled process running."""
    given, ports = [], []
    for name in ("one", "two"):
        session = Session(str(BRINGUP), {})
        port = MemoryPort(session.plan, name=name, host=f"robot-{name}")
        port.session = session
        port.happened(*(Started(p.id, pid=1000 + n)
                        for n, p in enumerate(session.plan.enabled_processes())))
        given.append((session, port))
        ports.append(port)
    app = FleetApp([("robot-one", "one"), ("robot-two", "two")], ports=given)
    async with app.run_test(size=(120, 32)) as pilot:
        await until(pilot, lambda: all(m.supervisor is not None and "running" in m.counts_text()
                                       for m in app.members), "both sessions followed")
        yield app, pilot, ports
        for port in ports:
            port.detached = True
            port.end(0)


def root(app: FleetApp, index: int) -> str:
    return str(app.members[index].tree.root.label)


async def on_root(pilot: Pilot[int], app: FleetApp, index: int) -> None:
    """The cursor on session `index`'s root row, its tree focused."""
    tree = app.members[index].tree
    tree.focus()
    await pilot.pause()
    tree.cursor_line = 0
    await until(pilot, lambda: app.current is app.members[index], "the session selected")


async def test_a_group_stop_asks_first_naming_the_session(tmp_path: Path) -> None:
    async with fleet() as (app, pilot, ports):
        await on_root(pilot, app, 1)
        await pilot.press("s")
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "a question")
        question = app.screen.question  # type: ignore[attr-defined]
        assert question.startswith("Stop all ") and "of robot-two:two" in question
        await pilot.press("n")
        await until(pilot, lambda: not isinstance(app.screen, ConfirmScreen), "answered")
        assert "stop" not in ports[0].ops() and "stop" not in ports[1].ops()


async def test_i_on_a_group_drops_the_keys_typed_with_it(tmp_path: Path) -> None:
    """`istop` Enter typed at once (as ssh delivers it) on a session's root: one line says
    why, and no key of it becomes a command (no question to stop, no tab switched)."""
    async with fleet() as (app, pilot, ports):
        await on_root(pilot, app, 0)
        for key in ["i", "s", "t", "o", "p", "enter", "2"]:  # one read of the terminal
            app.post_message(events.Key(key, None if key == "enter" else key))
        await until(pilot, lambda: any("were not sent" in str(n.message)
                                       for n in app._notifications), "the refusal said")
        await until(pilot, lambda: time.monotonic() >= app.dropping_until, "the burst over")
        assert not isinstance(app.screen, ConfirmScreen)
        assert app.tabs.active == "nodes"
        said = [str(n.message) for n in app._notifications]
        assert any(m.startswith("robot-one:one: ") and "not a node: i types into" in m
                   for m in said), said
        assert "stop" not in ports[0].ops() and "start" not in ports[0].ops()


async def test_a_lost_link_is_said_on_its_own_root_only(tmp_path: Path) -> None:
    async with fleet() as (app, pilot, ports):
        ports[1].link_lost = "link to robot-two lost (Connection refused)"
        await until(pilot, lambda: "link to robot-two lost" in root(app, 1), "its root says so")
        assert "lost" not in root(app, 0) and "running" in root(app, 0)
        ports[1].link_lost = None
        ports[1].silence = 7.0
        await until(pilot, lambda: "no word from robot-two for 7 s" in root(app, 1),
                    "a silent link said on its root")
        assert "no word" not in root(app, 0)


async def test_keys_act_on_the_focused_session_only(tmp_path: Path) -> None:
    async with fleet() as (app, pilot, ports):
        talker = next(p.id for p in app.members[0].session.plan.processes
                      if p.id.startswith("talker"))
        tree = app.members[1].tree
        tree.focus()
        await pilot.pause()
        tree.move_cursor(tree.rows[talker])
        await until(pilot, lambda: app.current is app.members[1], "session two selected")
        await pilot.press("s")
        await until(pilot, lambda: "stop" in ports[1].ops(), "two's talker stopped")
        assert ports[1].asked[-1] == ("stop", {"process": talker})
        assert "stop" not in ports[0].ops()
