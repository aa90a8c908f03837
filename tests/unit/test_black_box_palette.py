"""The command palette's black box over an in-memory session (memory_port.py): "Black box:
keep the last N s" asks the seconds and sends what `tuilaunch record NAME --black-box-on S`
sends; "Black box: write now" does what `b` does. Each by what the session is asked and
what the screen says."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from textual.command import CommandList, CommandPalette
from textual.widgets import Input

from tests.unit.test_app_pilot import following, toasts, until
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.tui.screens.dialogs import PathScreen


class BlackBox:
    """The session's black box as its server answers `black_box` (recorder.py's status)."""

    def __init__(self, seconds: float = 0.0, size: int = 0) -> None:
        self.seconds, self.size = seconds, size

    def __call__(self, **fields: Any) -> dict[str, Any]:
        if "seconds" in fields:
            self.seconds = float(fields["seconds"])
            self.size = int(fields.get("size") or 256 << 20) if self.seconds else 0
        return {"on": self.seconds > 0, "seconds": self.seconds, "size": self.size,
                "bytes": 0, "messages": 0, "topics": [], "files": []}


async def pick(pilot, app, words: str, title: str) -> None:  # type: ignore[no-untyped-def]
    """`:` then `words` typed in the palette, its one match `title` taken with Enter."""
    await pilot.press("colon", *words)
    await until(pilot, lambda: isinstance(app.screen, CommandPalette), "the palette")
    options = app.screen.query_one(CommandList)
    await until(pilot, lambda: [str(o.prompt).split("\n")[0] for o in options._options]
                == [title], f"{title} alone")
    await pilot.press("enter")


async def keep_asked(pilot, app) -> Input:  # type: ignore[no-untyped-def]
    """"Black box: keep the last N s" picked: its question on screen; its field."""
    await pick(pilot, app, "black box keep", "Black box: keep the last N s")
    await until(pilot, lambda: isinstance(app.screen, PathScreen), "the question")
    return app.screen.query_one(Input)


async def test_keep_the_last_n_seconds_asks_them_and_switches_the_black_box_on(
        tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.answers["black_box"] = BlackBox()
        field = await keep_asked(pilot, app)
        assert "now off" in app.screen.question and field.value == "30"
        field.value = ""
        await pilot.press(*"20", "enter")
        await until(pilot, lambda: ("black_box", {"seconds": 20.0}) in port.asked,
                    "the black box switched on with its seconds")
        await until(pilot, lambda: any("black box on: the last 20 s" in t for t in toasts(app)),
                    "said")
        # asked again, it offers what it keeps, and its bound in bytes stays as it is
        field = await keep_asked(pilot, app)
        assert "now the last 20 s" in app.screen.question and field.value == "20"
        field.value = ""
        await pilot.press("0", "enter")
        await until(pilot, lambda: ("black_box", {"seconds": 0.0, "size": 256 << 20})
                    in port.asked, "switched off")
        await until(pilot, lambda: "black box off" in toasts(app), "said off")


async def test_seconds_that_are_no_number_are_one_line_and_nothing_is_sent(
        tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.answers["black_box"] = BlackBox()
        field = await keep_asked(pilot, app)
        field.value = ""
        await pilot.press(*"-5", "enter")
        await until(pilot, lambda: any("'-5' is not a number of seconds" in t
                                       for t in toasts(app)), "said")
        assert [f for op, f in port.asked if op == "black_box"] == [{}]  # its status alone


async def test_write_now_writes_it_as_b_does_and_says_a_refusal(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.answers["black_box_write"] = lambda: {"path": "/log/black-box-now.mcap",
                                                   "messages": 12}
        await pick(pilot, app, "black box write", "Black box: write now")
        await until(pilot, lambda: "/log/black-box-now.mcap (12 messages)" in toasts(app),
                    "the file said")

        def off() -> None:
            raise SessionError("session bringup: the black box is off: start the launch "
                               "with --black-box SECONDS")

        port.answers["black_box_write"] = off
        await pilot.press("b")
        await until(pilot, lambda: any(t.startswith("the black box is off")
                                       for t in toasts(app)), "the refusal said")
        assert port.ops().count("black_box_write") == 2


async def test_a_read_only_view_offers_no_switch(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, _pilot, _port):
        app.read_only = True
        titles = [c.title for c in app.get_system_commands(app.screen)]
        assert "Black box: keep the last N s" not in titles
        assert "Black box: write now" in titles
