"""`w` and `y` give every line a pane stands for, over an in-memory session on another
machine (memory_port.py): the runs of lines a link did not send (a flood's, a reconnection's
beyond the scrollback), which the pane shows as one marker line each, are read through the
session first (`read_log`, paged as its server pages), and a save that could not read them
says so. The same on the shipped path (a real sshd, a dropped link, tmux):
tests/integration/test_remote_pane_export.py."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tests.unit.test_app_pilot import following, select, toasts, until
from tuilaunch.engine.run.events import Dropped, Output
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.tui.output_store import Gap, Line, read_back
from tuilaunch.tui.screens.output_panel import GapsRead

LOG = [[1.0 + n, "stdout", f"line {n}"] for n in range(1, 41)]
"""talker-1's log file, as `read_log` answers it: `line 1` ... `line 40`."""


class ReadLog:
    """`read_log` over LOG as the server answers it: from byte `start` (here: a line's
    number), after `skip` lines, at most `limit` (and `page` at most, as an answer that
    reached its size bound), `next` where to ask again."""

    def __init__(self, page: int = 1000) -> None:
        self.page = page
        self.asked: list[dict[str, Any]] = []

    def __call__(self, process: str, start: int = 0, skip: int = 0, limit: int = 0,
                 **rest: Any) -> dict[str, Any]:
        self.asked.append({"start": start, "skip": skip, "limit": limit})
        first = start + skip
        rows = LOG[first:first + min(limit, self.page)]
        return {"lines": rows, "next": first + len(rows), "size": len(LOG), "skipped": 0}


def saved(app) -> str:  # type: ignore[no-untyped-def]
    said = next(t for t in toasts(app) if t.startswith("pane saved to "))
    return Path(said.removeprefix("pane saved to ")).read_text()


async def flooded(pilot, app, port) -> None:  # type: ignore[no-untyped-def]
    """talker-1 said lines 1-5, then 30 lines the link did not send (6-35), then 36-40."""
    select(app, "talker-1")
    port.tell(Output("talker-1", stream="stdout", lines=[f"line {n}" for n in range(1, 6)]),
              Dropped("talker-1", code=30, data={"start": 0, "skip": 5}),
              Output("talker-1", stream="stdout", lines=[f"line {n}" for n in range(36, 41)]))
    await until(pilot, lambda: "line 40" in app.output_panel.pane_lines(), "the lines")
    assert "30 lines not drawn: scroll here to read" in app.output_panel.pane_lines()


async def test_w_saves_the_lines_the_link_did_not_send_in_place_of_their_marker(
        tmp_path: Path) -> None:
    async with following(tmp_path, host="robot1") as (app, pilot, port):
        reads = ReadLog(page=12)  # an answer at its bound: paged on from its `next`
        port.answers["read_log"] = reads
        await flooded(pilot, app, port)
        await pilot.press("w")
        await until(pilot, lambda: any(t.startswith("pane saved to") for t in toasts(app)),
                    "saved")
        lines = saved(app).splitlines()
        assert [line for line in lines if line.startswith("line ")] == \
            [f"line {n}" for n in range(1, 41)]
        assert not any("not drawn" in line for line in lines)
        assert reads.asked[0] == {"start": 0, "skip": 5, "limit": 30}
        assert reads.asked[1:] == [{"start": 17, "skip": 0, "limit": 18},
                                   {"start": 29, "skip": 0, "limit": 6}]
        # the pane is left as it was: scrolling back to the marker still reads it there
        assert "30 lines not drawn: scroll here to read" in app.output_panel.pane_lines()


async def test_y_copies_them_too(tmp_path: Path) -> None:
    async with following(tmp_path, host="robot1") as (app, pilot, port):
        port.answers["read_log"] = ReadLog()
        copied: list[str] = []
        app.copy_to_clipboard = copied.append  # type: ignore[method-assign]
        await flooded(pilot, app, port)
        await pilot.press("y")
        await until(pilot, lambda: copied, "copied")
        assert [line for line in copied[0].splitlines() if line.startswith("line ")] == \
            [f"line {n}" for n in range(1, 41)]
        assert any(t.startswith("copied ") for t in toasts(app))


async def test_a_save_whose_gaps_cannot_be_read_says_so_and_where_they_are(
        tmp_path: Path) -> None:
    async with following(tmp_path, host="robot1") as (app, pilot, port):
        def lost(**fields: Any) -> dict[str, Any]:
            raise SessionError("link to robot1 lost (ssh exit status 255): not sent "
                               "(read_log); reconnecting")

        port.answers["read_log"] = lost
        await flooded(pilot, app, port)
        await pilot.press("w")
        await until(pilot, lambda: any("30 lines not drawn could not be read" in t
                                       for t in toasts(app)), "the lines not read said")
        said = next(t for t in toasts(app) if "could not be read" in t)
        assert "link to robot1 lost" in said and "tuilaunch logs robot1:bringup talker-1" \
            in said, said
        text = saved(app)  # saved all the same, a line standing where they are missing
        assert "30 lines not drawn: scroll here to read" in text and "line 40" in text


def test_lines_read_back_are_parsed_as_lines_that_came():
    rows = [[5.0, "stderr", "\x1b[31m[ERROR] [12.5] [node]: bad\x1b[0m"], [6.0, "stdout", "x"]]
    lines = read_back("p", rows)
    assert [(line.text, line.level, line.stamp) for line in lines] == [
        ("[ERROR] [12.5] [node]: bad", 3, 12.5), ("x", 1, 6.0)]


def test_pane_lines_put_a_gaps_lines_where_its_marker_is():
    marker = Line("p", "2 lines not drawn", 1, gap=Gap(0, 0, 2))
    read = GapsRead({id(marker): read_back("p", [[1.0, "stdout", "a"], [2.0, "stdout", "b"]])})
    assert read.lines[id(marker)][1].text == "b" and read.unread == 0
