"""What the status line and the toasts say of the session itself, over an in-memory one
(memory_port.py): a link to its machine lost or silent, its end asked elsewhere, another
client's relaunch, the plan's warnings."""

from __future__ import annotations

from pathlib import Path

import pytest
from textual.css.query import NoMatches

from tests.unit.test_app_pilot import following, pane, row, select, status, toasts, until
from tuilaunch.engine.run.events import ProcessExited, Relaunched, Started
from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.screens.fields import Field


def preview(app: TuiLaunchApp) -> str:
    return str(app.query_one("#args-preview").render())


def form_value(app: TuiLaunchApp, name: str) -> str | None:
    """An argument's value in the Args form (None while the form is drawn again)."""
    try:
        return app.args_tab.panel.values()[name]
    except NoMatches:
        return None


async def test_a_lost_link_is_said_first_with_its_reason_and_r_retries(tmp_path: Path) -> None:
    async with following(tmp_path, host="robot1") as (app, pilot, port):
        assert status(app).startswith("[robot1:bringup] bringup.py  5 running")
        port.link_lost = "12:00:01"
        port.lost_reason = "ssh: connect to host robot1 port 22: Connection refused"
        await until(pilot, lambda: status(app).startswith(
            "link to robot1 lost · reconnecting · bringup · R: now · "),
            "the lost link first")
        # the reason's end, which says what went wrong, within 80 columns
        assert "… Connection refused  bringup.py  5 running" in status(app)
        await pilot.press("R")
        await until(pilot, lambda: "retry" in port.ops(), "a retry asked at once")
        assert "reconnecting to robot1" in toasts(app)
        port.link_lost = port.lost_reason = None
        await until(pilot, lambda: status(app).startswith("[robot1:bringup]"), "back")


async def test_a_silent_link_says_how_long_after_five_seconds(tmp_path: Path) -> None:
    async with following(tmp_path, host="robot1") as (app, pilot, port):
        port.silence = 3.0  # a pause a link has: nothing said yet
        await pilot.pause(0.3)
        assert "no word" not in status(app)
        port.silence = 7.2
        await until(pilot, lambda: status(app).startswith("no word from robot1 for 7 s · "),
                    "the silence counted")
        port.silence = 0.0
        await until(pilot, lambda: "no word" not in status(app), "a word came")


async def test_r_with_no_link_down_says_so(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await pilot.press("R")
        await until(pilot, lambda: "no link is down" in toasts(app), "said")
        assert "retry" not in port.ops()


async def test_a_session_stopped_elsewhere_says_so_before_leaving(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # the words stay until the test has read them, however late a loaded machine runs it
    monkeypatch.setattr("tuilaunch.tui.session_link.ENDED_ELSEWHERE_PAUSE", 600.0)
    async with following(tmp_path) as (app, pilot, port):
        port.end(0, reason="tuilaunch stop")
        said = "session bringup was stopped elsewhere (tuilaunch stop); leaving"
        await until(pilot, lambda: status(app) == said, "the status line saying why")
        assert said in toasts(app)


async def test_another_clients_relaunch_is_said_and_the_form_follows(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.tell(Relaunched(None, lines=["robot:=r2"]),
                  ProcessExited("talker-1", pid=1000, code=-2, reason="killed by SIGINT",
                                data={"again": True}),
                  Started("talker-1", pid=2000))
        await until(pilot, lambda: "relaunched by another client: robot:=r2" in toasts(app),
                    "the relaunch said")
        await until(pilot, lambda: row(app, "talker-1") == "● talker-1 running pid 2000",
                    "talker-1 started again")
        # an edit starts from what runs
        await until(pilot, lambda: form_value(app, "robot") == "r2", "the form's value")
        await until(pilot, lambda: status(app).endswith("robot:=r2"), "the header's values")
        select(app, "talker-1")
        await until(pilot, lambda: "/r2/" in str(app.detail_bar.render()), "its new name")


async def test_a_row_chosen_as_soon_as_a_relaunch_redraws_the_tree_is_selected(
        tmp_path: Path) -> None:
    """The tree drawn again (a relaunch) and a row chosen before it has painted (`a`, or a
    selection in the same tick): that row is selected, not none. A loaded machine ran a
    look between the redraw and the paint; this makes that moment happen every time."""
    async with following(tmp_path) as (app, pilot, port):
        port.tell(Relaunched(None, lines=["robot:=r2"]))
        await until(pilot, lambda: form_value(app, "robot") == "r2", "the relaunch taken")
        tree = app.launch_tree
        tree.show_plan(port.plan, dict(tree.states))  # no await: nothing painted in between
        select(app, "talker-1")
        assert tree.cursor_node is tree.rows["talker-1"]
        await until(pilot, lambda: "/r2/" in str(app.detail_bar.render()), "its new name")
        tree.show_plan(port.plan, dict(tree.states))
        app.nodes.show_all()  # `a`, in the same tick as a redraw
        assert tree.cursor_node is tree.root.children[0]


async def test_an_edit_not_applied_gives_way_to_another_clients_relaunch(
        tmp_path: Path) -> None:
    """The form keeps its editors and takes the values that run now: what was typed and
    not applied is gone, and the form is not left looking edited."""
    async with following(tmp_path) as (app, pilot, port):
        await pilot.press("a")
        editor = app.query_one("#arg-robot", Field)
        editor.value = "r9"
        await until(pilot, lambda: "would" in preview(app), "the edit previewed")
        port.tell(Relaunched(None, lines=["robot:=r2"]))
        await until(pilot, lambda: form_value(app, "robot") == "r2", "the running value")
        assert app.query_one("#arg-robot", Field) is editor  # not drawn anew
        await pilot.press("f5")
        await until(pilot, lambda: "nothing to apply" in toasts(app), "nothing left to apply")
        assert "relaunch" not in port.ops()


async def test_a_relaunch_before_this_client_came_is_no_news(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.tell(Relaunched(None, lines=["robot:=r3"], time=app.opened_at - 60))
        await until(pilot, lambda: form_value(app, "robot") == "r3",
                    "the form showing what runs")
        assert not any("relaunched" in t for t in toasts(app))


async def test_an_undeclared_argument_is_said_apart_and_in_the_all_nodes_pane(
        tmp_path: Path) -> None:
    async with following(tmp_path, arguments={"robto": "r2"}) as (app, pilot, _port):
        # a typo applies nothing: said first, never listed with what applies
        assert status(app).startswith("[bringup] bringup.py  5 running  not declared: robto")
        assert "robto:=" not in status(app)
        select(app, "all nodes")
        await until(pilot, lambda: any(line.startswith("[launch] warning:") and "robto" in line
                                       for line in pane(app)), "the warning, kept")
        assert any("did you mean 'robot'?" in line for line in pane(app))


async def test_over_a_link_the_selected_nodes_figures_are_asked_for_while_nothing_comes(
        tmp_path: Path) -> None:
    """Over a link the status line is redrawn each tick (a silence is counted); the detail
    line only when something came: its redraw restarts the wait after which the figures
    of the selected node are asked for, so at each tick they never were."""
    async with following(tmp_path, host="robot1") as (app, pilot, port):
        select(app, "listener-2")

        def trend_asked() -> bool:
            return any(op == "watch_resources" and "listener-2" in (fields.get("trend") or [])
                       for op, fields in port.asked)

        await until(pilot, trend_asked, "the selected node's trend asked for")
