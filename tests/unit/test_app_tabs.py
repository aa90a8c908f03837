"""The tabs over an in-memory session (memory_port.py): the keys 1-5 and where each tab
puts the cursor, the Args form as the plan declares its arguments, an edit's preview
(a type warning, what would restart, a name ROS refuses) and F5's relaunch asked of the
session."""

from __future__ import annotations

from pathlib import Path

from textual.widgets import Label, Select, Static
from textual.widgets._footer import FooterKey

from tests.unit.test_app_pilot import following, footer, row, select, status, toasts, until
from tuilaunch.tui.app import TuiLaunchApp


def preview(app: TuiLaunchApp) -> str:
    """The Args tab's line above the form: what the edits would do."""
    return str(app.args_tab.panel.query_one("#args-preview", Static).render())


def form(app: TuiLaunchApp) -> dict[str, tuple[str, str]]:
    """Each argument's row of the form: its editor's kind and its help line."""
    rows = {}
    for row_ in app.args_tab.panel.query(".arg-row"):
        name = str(row_.query_one(Label).render())
        help_line = str(row_.query_one(".arg-help", Static).render())
        rows[name] = (type(row_.query_one(".arg-editor")).__name__, help_line)
    return rows


async def test_the_digit_keys_open_each_tab_where_its_work_starts(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        starts = {"2": ("args", "apply"), "3": ("services", "svc-list"),
                  "4": ("params", "prm-nodes"), "5": ("topics", "tpc-table"),
                  "1": ("nodes", "tree")}
        for key, (tab, focus) in starts.items():
            await pilot.press(key)
            await until(pilot, lambda tab=tab, focus=focus: app.tabs.active == tab and
                        app.focused is not None and app.focused.id == focus,
                        f"{key}: the {tab} tab, on its {focus}")
        # the graph tabs asked the session, where the nodes run, when first shown
        assert {"services", "nodes", "topics"} <= set(port.ops())


async def test_the_footer_offers_each_tabs_own_keys(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, _port):
        await pilot.press("5")
        await until(pilot, lambda: {"Echo", "Plot", "Filter"} <= set(footer(app)),
                    "the Topics tab's keys")
        assert "Stop" not in footer(app)  # a node's keys are the Nodes tab's
        await pilot.press("4")
        await until(pilot, lambda: {"Write file", "Load file"} <= set(footer(app)),
                    "the Params tab's keys")
        await pilot.press("1")
        await until(pilot, lambda: {"Stop", "Restart", "Search", "Level"}
                    <= set(footer(app)), "the Nodes tab's keys")


def stop_key(app: TuiLaunchApp) -> FooterKey:
    return next(k for k in app.screen.query(FooterKey) if k.description == "Stop")


async def test_a_tap_on_a_footer_key_counts_though_the_keys_were_refreshed_meanwhile(
        tmp_path: Path) -> None:
    """A tap is a press and a release on the same key. The keys refreshed between the two
    (a row's selection, a focus move; a browser's tap under load) draw the same keys: the
    footer keeps its keys, and the tap stops the node."""
    async with following(tmp_path, size=(160, 30)) as (app, pilot, port):
        select(app, "talker-1")
        await until(pilot, lambda: footer(app).get("Stop") is True and "Type" in footer(app)
                    and stop_key(app).region.width > 0, "a node's keys on screen")
        stop = stop_key(app)
        await pilot.mouse_down(stop)
        app.refresh_bindings()
        await pilot.pause()
        await pilot.mouse_up(stop)
        await until(pilot, lambda: ("stop", {"process": "talker-1"}) in port.asked,
                    "talker-1 stopped by the tap")
        assert stop.is_attached


async def test_the_args_form_shows_every_argument_its_help_and_editor(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, _port):
        await pilot.press("2")
        await until(pilot, lambda: app.tabs.active == "args", "the Args tab")
        rows = form(app)
        assert list(rows) == ["robot", "rate", "listener", "services", "mode", "topic"]
        assert rows["robot"] == (
            "Field", "robot name, used as the namespace of its nodes  [default 'r1', str]")
        assert rows["rate"] == (
            "Field", "talker publishing rate [Hz]  [default '2.0', float]")
        assert rows["listener"][0] == "Toggle"
        assert rows["mode"][0] == "Select"
        # an included file's argument says where it is declared
        assert rows["topic"][1].endswith("from monitor.launch.py")
        mode = app.args_tab.panel.query_one("#arg-mode", Select)
        assert [value for _, value in mode._options] == ["idle", "patrol", "dock"]
        assert mode.value == "patrol"


async def test_the_form_shows_the_values_the_session_runs_with(tmp_path: Path) -> None:
    async with following(tmp_path, arguments={"robot": "r7", "listener": "false"}) \
            as (app, pilot, _port):
        await pilot.press("2")
        await until(pilot, lambda: app.tabs.active == "args", "the Args tab")
        panel = app.args_tab.panel
        assert panel.values()["robot"] == "r7"
        assert panel.values()["listener"] == "false"  # the spelling given, kept
        # a value unlike its default is highlighted
        assert panel.query_one("#row-robot").has_class("changed")
        assert not panel.query_one("#row-rate").has_class("changed")


async def test_an_edit_unlike_its_defaults_type_is_warned_of_and_previewed(
        tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await pilot.press("2", "tab", "tab", "ctrl+u", *"fast")
        await until(pilot, lambda: "fast" in preview(app), "the preview of rate:=fast")
        assert preview(app) == (
            "Warning: argument 'rate' = 'fast' is not a number like its default 2.0 "
            "(passed as written); would restart: talker-1.  F5 applies.")
        assert row(app, "talker-1").startswith("+")  # marked in the tree
        assert "apply" not in port.ops()  # a preview relaunches nothing


async def test_a_name_ros_refuses_is_never_applied(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await pilot.press("2", "tab", "ctrl+u", *"1bad")
        await until(pilot, lambda: preview(app).startswith("Cannot apply"), "refused")
        assert "namespace '/1bad'" in preview(app)
        await pilot.press("f5")
        await until(pilot, lambda: any("cannot apply" in t for t in toasts(app)),
                    "F5 saying it cannot apply")
        assert "apply" not in port.ops()


async def test_f5_relaunches_with_the_forms_values(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await pilot.press("2", "tab", "ctrl+u", *"r2")
        await until(pilot, lambda: "would restart" in preview(app), "the preview")
        await pilot.press("f5")
        await until(pilot, lambda: "apply" in port.ops(), "the relaunch asked")
        applied = dict(port.asked)["apply"]["arguments"]
        assert applied["robot"] == "r2" and applied["rate"] == "2.0"
        await until(pilot, lambda: preview(app).startswith("Applied. Stopped: talker-1"),
                    "what the relaunch stopped and started")
        await until(pilot, lambda: status(app).endswith("robot:=r2"),
                    "the header's values")


async def test_f5_with_nothing_edited_relaunches_nothing(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        await pilot.press("f5")
        await until(pilot, lambda: "nothing to apply" in toasts(app), "F5 saying so")
        assert "apply" not in port.ops()
