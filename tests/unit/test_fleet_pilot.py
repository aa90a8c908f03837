"""The fleet view's rules under Pilot, over two in-memory sessions (memory_port.py): the
single TUI's rules hold on each session of a fleet (a group's stop asks, naming the
session; `i` on a group drops its burst; a lost link is said on its own root only), and a
key acts on the focused session alone. `i` types into a node right in the fleet view (the
single TUI's keyboard, one per session: a browser's page cannot hand its terminal to
another TUI), the keys typed with it held for the node; a node started with pipes is
offered a terminal first, the question naming its session."""

from __future__ import annotations

import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from functools import partial
from pathlib import Path

from textual import events
from textual.pilot import Pilot

from tests.unit.memory_port import MemoryPort
from tests.unit.test_app_pilot import BRINGUP, _walk, footer, until
from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.events import Started
from tuilaunch.tui.fleet import app as fleet_app
from tuilaunch.tui.fleet.app import FleetApp
from tuilaunch.tui.fleet.bindings import BINDINGS
from tuilaunch.tui.inspect.inspector import INSPECTOR_BINDINGS
from tuilaunch.tui.keys.keyboard import KEYBOARD_BINDINGS
from tuilaunch.tui.screens.dialogs import ConfirmScreen
from tuilaunch.tui.screens.interact_dialogs import TerminalQuestion, TypingLine
from tuilaunch.tui.screens.output_panel import PANE_BINDINGS, NodesView


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


def burst(app: FleetApp, keys: str | list[str]) -> None:
    """Keys read at once from the terminal (as ssh delivers a line typed fast)."""
    for key in keys:
        app.post_message(events.Key(key, "\r" if key == "enter" else key))


def said(app: FleetApp) -> list[str]:
    return [str(n.message) for n in app._notifications]


def refusal_said(app: FleetApp, label: str) -> bool:
    return any(m.startswith(f"{label}: ") and "were not sent" in m for m in said(app))


async def on_row(pilot: Pilot[int], app: FleetApp, index: int, row: str) -> str:
    """The cursor on the row of session `index` whose process id or label starts with
    `row` (`talker`, `ns /r1/control`); its id, or its label."""
    tree = app.members[index].tree
    tree.focus()
    await pilot.pause()
    node = next(n for n in _walk(tree.root) if n is not tree.root and any(
        text.startswith(row) for text in (n.data.ref or "", str(n.label), str(n.label)[2:])))
    tree.move_cursor(node)
    await until(pilot, lambda: app.current is app.members[index] and
                tree.cursor_node is node, "the row selected")
    return node.data.ref or str(node.label)


async def test_i_on_a_group_drops_the_keys_typed_with_it(tmp_path: Path) -> None:
    """`istop` Enter typed at once (as ssh delivers it) on a session's root, and on a group
    of the other session: one line says why, and no key of it becomes a command (no
    question to stop, no tab switched)."""
    async with fleet() as (app, pilot, ports):
        for index, label in ((0, "robot-one:one"), (1, "robot-two:two")):
            if index == 0:
                await on_root(pilot, app, 0)
            else:
                await on_row(pilot, app, 1, "ns /r1")
            burst(app, ["i", "s", "t", "o", "p", "enter", "2"])
            await until(pilot, partial(refusal_said, app, label), "the refusal said")
            await until(pilot, lambda: time.monotonic() >= app.dropping_until,
                        "the burst over")
            assert not isinstance(app.screen, ConfirmScreen)
            assert app.tabs.active == "nodes"
            assert any(m.startswith(f"{label}: ") and "not a node: i types into" in m
                       for m in said(app)), said(app)
            for port in ports:
                assert not {"stop", "start", "typing", "input"} & set(port.ops())


async def test_i_types_into_a_node_of_the_second_session_in_the_fleet_view(
        tmp_path: Path, monkeypatch) -> None:
    """`i` on robot-two's talker: a typing line in the fleet's own screen (no other TUI
    run: nothing suspends, as a browser's page cannot), the keys typed with `i` in one
    burst held for the node and sent to it (`stop` Enter stops nothing), the footer
    offering only ctrl+] meanwhile; ctrl+] gives the keys back to the fleet."""
    ran: list[object] = []
    monkeypatch.setattr(fleet_app.subprocess, "run", lambda *a, **k: ran.append(a))
    async with fleet() as (app, pilot, ports):
        talker = await on_row(pilot, app, 1, "talker")
        burst(app, ["i", "s", "t", "o", "p", "enter"])
        keyboard = app.members[1].keyboard
        await until(pilot, lambda: keyboard.typing_to == talker, "typing into the talker")
        assert ("typing", {"on": True, "process": talker}) in ports[1].asked
        await until(pilot, lambda: "".join(f["data"] for op, f in ports[1].asked
                                           if op == "input") == "stop\r",
                    "the keys typed with i sent to the node")
        line = app.screen.query_one(TypingLine)
        assert app.focused is line
        assert f"typing to {talker} of robot-two:two" in str(line.render())
        # s, q... are the node's now (the footer is drawn anew for the typing line: wait for it)
        await until(pilot, lambda: list(footer(app)) == ["Give the keys back"],
                    "a footer offering only ctrl+]")
        await pilot.press("q", "s")
        await until(pilot, lambda: "".join(f["data"] for op, f in ports[1].asked
                                           if op == "input") == "stop\rqs", "q and s typed")
        assert not app.detached and "stop" not in ports[1].ops()
        await pilot.press("ctrl+right_square_bracket")
        await until(pilot, lambda: keyboard.typing_to is None, "the keys given back")
        await until(pilot, lambda: ("typing", {"process": talker})
                    in ports[1].asked, "the node's keyboard given back")
        await until(pilot, lambda: not app.screen.query(TypingLine), "the line gone")
        assert app.focused is app.members[1].tree
        assert not {"typing", "input", "stop"} & set(ports[0].ops())  # robot-one: untouched
        assert ran == []


async def test_a_node_with_pipes_is_offered_a_terminal_naming_its_session(
        tmp_path: Path) -> None:
    """`i` on a node its file started with pipes: the question names the session, No
    focused; a `y` typed with the `i` never answers it (dropped, said); `n` leaves the node
    as it is; `y` restarts it with a terminal on its own session and types into it."""
    async with fleet() as (app, pilot, ports):
        talker = await on_row(pilot, app, 1, "talker")
        ports[1].answers["status"] = lambda **_: {"processes": [
            {"id": talker, "state": "running", "terminal": False}]}
        burst(app, ["i", "y", "s"])
        await until(pilot, lambda: isinstance(app.screen, TerminalQuestion), "the question")
        question = app.screen.question  # type: ignore[attr-defined]
        assert question.startswith(f"{talker} of robot-two:two has no terminal to type into")
        assert question.endswith("Restart it with a terminal (until its next plain "
                                 "restart) and type into it?")
        await until(pilot, lambda: app.focused is not None and app.focused.id == "no",
                    "No focused")
        await until(pilot, lambda: any("answer the question with a key typed now" in m
                                       for m in said(app)), "the y typed with i dropped")
        await until(pilot, lambda: time.monotonic() >= app.dropping_until, "the burst over")
        assert isinstance(app.screen, TerminalQuestion)  # the y answered nothing
        await pilot.press("n")
        await until(pilot, lambda: not isinstance(app.screen, TerminalQuestion), "answered")
        assert not {"restart", "stop", "typing"} & set(ports[1].ops())
        # the keys of the burst that answered no are dropped with it: an `i` typed after it
        await until(pilot, lambda: time.monotonic() >= app.dropping_until, "its burst over")
        await pilot.press("i")
        await until(pilot, lambda: isinstance(app.screen, TerminalQuestion), "asked again")
        # a key of the burst of that `i` would be dropped with it: `y` is typed after it
        await until(pilot, lambda: time.monotonic() >= app.dropping_until, "its burst over")
        await pilot.press("y")
        await until(pilot, lambda: app.members[1].keyboard.typing_to == talker,
                    "typing once restarted with a terminal")
        assert ("restart", {"process": talker, "terminal": True}) in ports[1].asked
        assert talker in app.members[1].asked_to_stop  # its exit is no failure
        assert not {"restart", "typing"} & set(ports[0].ops())


def test_the_fleet_binds_the_single_tuis_keyboard_inspector_and_pane_keys() -> None:
    """One list of keys for both views: the fleet's i, g, c, o, L, b and the pane's keys
    are the single TUI's bindings themselves, and FleetApp stays within its budget of
    methods."""
    for binding in [*KEYBOARD_BINDINGS, *INSPECTOR_BINDINGS, *PANE_BINDINGS]:
        assert binding in BINDINGS
    assert NodesView.BINDINGS is PANE_BINDINGS
    methods = [name for name, value in vars(FleetApp).items() if callable(value)
               and not isinstance(value, type)]
    assert len(methods) <= 50, sorted(methods)


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


async def test_the_footer_offers_the_node_keys_first_and_the_tree_column_resizes(
        tmp_path: Path) -> None:
    """On a node, the footer starts with the single TUI's keys (a tablet's browser shows
    them whole: tests/integration/test_serve_fleet.py); `>` and `<` widen and narrow the
    trees' column, as they do the single TUI's tree."""
    async with fleet() as (app, pilot, _ports):
        await on_row(pilot, app, 1, "talker")
        await until(pilot, lambda: footer(app).get("Type") is True, "Type offered")
        shown = list(footer(app))
        assert shown[:10] == ["Type", "Debug", "Nodes", "Args", "Services", "Params", "Stop",
                              "Restart", "Start", "Search"], shown
        trees = app.query_one("#fleet-trees")
        width = trees.outer_size.width
        await pilot.press("greater_than_sign")
        await until(pilot, lambda: trees.outer_size.width == width + 4, "wider")
        await pilot.press("less_than_sign", "less_than_sign")
        await until(pilot, lambda: trees.outer_size.width == width - 4, "narrower")
