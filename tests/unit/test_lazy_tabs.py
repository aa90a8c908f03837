"""The Services, Params and Topics tabs are made the first time they are shown (issue 45: pay
for what you use): until then neither their widgets nor their modules exist, and what the
session sends for them meanwhile is no error; once shown they work as a tab made at start,
the keys typed right after the tab key included."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from textual import events
from textual.widgets import Input, Static

from tests.unit.memory_port import MemoryPort
from tests.unit.test_app_pilot import BRINGUP, following, until
from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.events import Echo, Rates
from tuilaunch.tui.app import TuiLaunchApp

PANELS = {"3": ("services", "#services-panel", "#svc-list"),
          "4": ("params", "#params-panel", "#prm-nodes"),
          "5": ("topics", "#topics-panel", "#tpc-table")}


def made(app: TuiLaunchApp) -> set[str]:
    """The lazy tabs whose panel exists."""
    return {tab for tab, panel, _ in PANELS.values() if app.tabs.query(panel)}


def test_the_app_imports_no_panel_of_a_tab_not_shown() -> None:
    loaded = subprocess.run(
        [sys.executable, "-c", "import sys, tuilaunch.tui.app\n"
         "print(sorted(m for m in sys.modules if m.endswith(('services_panel', "
         "'params_panel', 'topics_panel', 'session_graph'))))"],
        capture_output=True, text=True, timeout=60, check=True).stdout.strip()
    assert loaded == "[]"


async def test_a_tab_is_made_when_first_shown_and_works_then(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        assert made(app) == set() and app.topics_panel is None
        assert not {"services", "nodes", "topics"} & set(port.ops())  # nobody asked yet
        for key, (tab, _panel, home) in PANELS.items():
            await pilot.press(key)
            await until(pilot, lambda tab=tab, home=home: app.tabs.active == tab and
                        app.focused is app.tabs.query_one(home), f"{key}: {tab}, on {home}")
            assert tab in made(app)
        assert made(app) == {"services", "params", "topics"}
        # each asks the session for its part of the graph once on screen (a worker's
        # request: it may come a moment after the focus)
        await until(pilot, lambda: {"services", "nodes", "topics"} <= set(port.ops()),
                    "each tab's part of the graph asked for")
        await pilot.press("1", "3")  # shown again: the same panel, not a second one
        await until(pilot, lambda: app.tabs.active == "services", "Services again")
        assert len(app.tabs.query("#services-panel")) == 1


async def test_keys_typed_right_after_the_tab_key_reach_the_new_panel(tmp_path: Path) \
        -> None:
    async with following(tmp_path) as (app, pilot, _port):
        for key, character in (("4", "4"), ("slash", "/"), ("t", "t"), ("a", "a")):
            # one read of the terminal, as ssh delivers it: the panel is made meanwhile
            app.post_message(events.Key(key, character))
        await until(pilot, lambda: [field.value for field in app.tabs.query("#prm-filter")
                                    .results(Input)] == ["ta"],
                    "the params filter holds what was typed")
        assert app.tabs.active == "params"


async def test_readings_before_the_topics_tab_is_shown_are_dropped_and_it_shows_now(
        tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.tell(Rates(data={"/chatter": {"rate_hz": 10.0}}), Echo(data={"text": "x"}))
        await pilot.pause(0.3)
        assert app.is_running and app.topics_panel is None
        port.answers["topics"] = lambda **_: {"topics": [
            {"name": "/chatter", "types": ["std_msgs/msg/String"], "publishers": [],
             "subscribers": []}]}
        await pilot.press("5")
        await until(pilot, lambda: app.topics_panel is not None and
                    "/chatter" in app.topics_panel.entries, "the topics the session has now")
        await until(pilot, lambda: "watch_rates" in port.ops(), "its rates asked for")


async def test_a_click_on_a_tab_never_shown_makes_its_panel(tmp_path: Path) -> None:
    async with following(tmp_path, size=(100, 30)) as (app, pilot, _port):
        await pilot.click("#--content-tab-topics")
        await until(pilot, lambda: app.tabs.active == "topics" and app.topics_panel is not
                    None and app.focused is app.tabs.query_one("#tpc-table"),
                    "the Topics tab, its table focused")
        scope = app.topics_panel.query_one("#tpc-scope", Static)
        assert str(scope.render()) == "all topics"


async def test_attach_tab_opens_on_a_tab_never_shown(tmp_path: Path) -> None:
    """`tuilaunch attach NAME --tab topics`: the Topics tab, its panel made, once followed."""
    session = Session(str(BRINGUP), {})
    port = MemoryPort(session.plan, name="bringup")
    app = TuiLaunchApp(session, tmp_path, session_name="bringup", port=port)
    app.first_tab = "topics"
    async with app.run_test(size=(80, 24)) as pilot:
        await until(pilot, lambda: app.tabs.active == "topics" and app.topics_panel is not
                    None and app.focused is app.tabs.query_one("#tpc-table"),
                    "the Topics tab, its table focused")
        await until(pilot, lambda: "topics" in port.ops(), "the topics asked for")
        port.detached = True
        port.end(0)
