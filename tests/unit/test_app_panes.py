"""The output pane over an in-memory session (memory_port.py): which node's lines it shows
as the cursor moves, all nodes' with their ids, and its search (`/`, `n`), level (`l`) and
text filter (`\\`), as its status line and its lines say them."""

from __future__ import annotations

from pathlib import Path

from tests.unit.test_app_pilot import (
    following,
    pane,
    pane_status,
    select,
    toasts,
    until,
)
from tuilaunch.engine.run.events import Output

TALKER = [
    "[INFO] [1700000000.100000000] [r1.talker]: Publishing: hello 1",
    "[WARN] [1700000000.200000000] [r1.talker]: battery low",
    "[INFO] [1700000000.300000000] [r1.talker]: Publishing: hello 2",
    "[ERROR] [1700000000.400000000] [r1.talker]: lost the map",
]
MONITOR = ["[INFO] [1700000000.150000000] [monitor]: heard hello 1"]


async def told(pilot, app, port) -> None:  # type: ignore[no-untyped-def]
    """The talker's and the monitor's lines said by the session, talker-1 selected."""
    select(app, "talker-1")
    port.tell(Output("talker-1", stream="stderr", lines=TALKER),
              Output("monitor-5", stream="stderr", lines=MONITOR))
    await until(pilot, lambda: any("lost the map" in line for line in pane(app)),
                "talker-1's lines in its pane")


async def test_the_pane_follows_the_selected_node(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        assert not any("heard hello" in line for line in pane(app))
        assert pane_status(app).startswith("talker-1  DEBUG+")
        select(app, "monitor-5")
        await until(pilot, lambda: any("heard hello 1" in line for line in pane(app)),
                    "monitor-5's line once its row is selected")
        assert not any("battery low" in line for line in pane(app))
        assert pane_status(app).startswith("monitor-5")


async def test_all_nodes_shows_every_line_led_by_its_process(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        select(app, "all nodes")
        await until(pilot, lambda: pane_status(app).startswith("all nodes"), "all nodes")
        lines = pane(app)
        assert any(line.startswith("[talker-1]") and "battery low" in line for line in lines)
        assert any(line.startswith("[monitor-5]") and "heard hello 1" in line
                   for line in lines)
        # the session's start of each process, as ros2 launch prints it
        assert "[talker-1] process started with pid [1000]" in lines


async def test_a_key_shows_all_nodes_from_any_row(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        await pilot.press("a")
        await until(pilot, lambda: pane_status(app).startswith("all nodes"), "all nodes")
        assert any("heard hello 1" in line for line in pane(app))


async def test_slash_searches_and_n_moves_between_matches(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        await pilot.press("slash", *"hello", "enter")
        await until(pilot, lambda: "/hello 1/2" in pane_status(app), "the first of 2 matches")
        await pilot.press("n")
        await until(pilot, lambda: "/hello 2/2" in pane_status(app), "the second match")
        await pilot.press("n")
        await until(pilot, lambda: "/hello 1/2" in pane_status(app), "back to the first")
        # the search selected nothing of the tree: talker-1 was never stopped (`s` in
        # `/set` must not be a stop either)
        assert "stop" not in port.ops()


async def test_a_search_that_finds_nothing_says_so(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        await pilot.press("slash", *"zebra", "enter")
        await until(pilot, lambda: "/zebra no line matches" in pane_status(app),
                    "no match in the pane's status line")
        await until(pilot, lambda: "no line matches 'zebra'" in toasts(app), "a toast")


async def test_escape_clears_the_search(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        await pilot.press("slash", *"hello", "enter")
        await until(pilot, lambda: "/hello" in pane_status(app), "the search")
        await pilot.press("escape")
        await until(pilot, lambda: "/hello" not in pane_status(app), "the search cleared")
        assert app.focused is app.launch_tree  # back where `/` was typed


async def test_l_steps_the_level_up_and_hides_the_lines_below(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        await pilot.press("l")
        await until(pilot, lambda: pane_status(app).startswith("talker-1  INFO+"), "INFO+")
        await pilot.press("l")
        await until(pilot, lambda: pane_status(app).startswith("talker-1  WARN+"), "WARN+")
        lines = pane(app)
        assert any("battery low" in line for line in lines)
        assert any("lost the map" in line for line in lines)
        assert not any("Publishing" in line for line in lines)
        # tuilaunch's own line of the start is INFO: hidden at WARN+ too
        assert not any("process started" in line for line in lines)


async def test_a_level_that_hides_every_line_says_which_key_undoes_it(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        select(app, "monitor-5")
        port.tell(Output("monitor-5", stream="stderr", lines=MONITOR))
        await until(pilot, lambda: any("heard" in line for line in pane(app)), "its line")
        await pilot.press("l", "l")
        await until(pilot, lambda: "WARN+" in pane_status(app), "WARN+")
        assert pane(app) == []
        assert app.output_panel.line_view.empty_text == \
            "no line at WARN or above (l: next level)"


async def test_backslash_filters_lines_and_escape_shows_all_again(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        await pilot.press("backslash", *"hello", "enter")
        await until(pilot, lambda: "only 'hello'" in pane_status(app), "the filter said")
        lines = pane(app)
        assert len(lines) == 2 and all("hello" in line for line in lines), lines
        await pilot.press("escape")
        await until(pilot, lambda: "only" not in pane_status(app), "the filter cleared")
        assert any("battery low" in line for line in pane(app))


async def test_a_filter_that_hides_every_line_says_so(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        await pilot.press("backslash", *"zebra", "enter")
        await until(pilot, lambda: pane(app) == [], "every line hidden")
        assert app.output_panel.line_view.empty_text == \
            "no line matches 'zebra' (esc: show all)"


async def test_new_lines_of_another_node_do_not_enter_the_pane(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await told(pilot, app, port)
        before = pane(app)
        port.tell(Output("monitor-5", stream="stdout", lines=["heard hello 2"]),
                  Output("talker-1", stream="stdout", lines=["plain print"]))
        await until(pilot, lambda: any("plain print" in line for line in pane(app)),
                    "talker-1's new line")
        assert pane(app) == [*before, "plain print"]
