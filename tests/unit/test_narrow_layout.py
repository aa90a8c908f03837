"""The Nodes tab on a phone (issue 46): below 70 columns (a browser 390 px wide shows about
42) the tree goes above the output pane, so a long node name shows whole on its row;
wider, the tree stays beside the pane. In a browser (cli/serve_tab.py) a phone's footer
offers the node's keys in two rows, the palette at its right end.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from textual.widget import Widget
from textual.widgets import Footer
from textual.widgets._footer import FooterKey

from tests.unit.test_app_pilot import following, until
from tuilaunch.cli.serve_tab import compact_footers, phone_footers
from tuilaunch.tui.app import TuiLaunchApp

LONG = "a_very_long_node_name_of_30_ch"
assert len(LONG) == 30

LAUNCH = f"""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='ticker', cmd=['sleep', '600']),
        ExecuteProcess(name='{LONG}', cmd=['sleep', '600']),
        ExecuteProcess(name='echo', cmd=['sleep', '600'])])
"""


def launch_file(tmp_path: Path) -> Path:
    path = tmp_path / "long_launch.py"
    path.write_text(LAUNCH)
    return path


def tree_rows(app: TuiLaunchApp) -> list[str]:
    """The tree's rows as drawn, cut at its width."""
    tree = app.launch_tree
    return [tree.render_line(y).text for y in range(tree.size.height)]


def shown(app: TuiLaunchApp, widget: Widget) -> bool:
    """The widget has room on the screen (not squeezed to nothing, not below it)."""
    region = widget.region
    return region.width > 0 and region.height > 0 and region.bottom <= app.size.height


async def test_a_phone_has_the_tree_above_the_pane_and_names_whole(tmp_path: Path) -> None:
    async with following(tmp_path / "run", launch_file(tmp_path), size=(42, 40),
                         name="long") as (app, pilot, _):
        tree, pane = app.launch_tree, app.output_panel
        await until(pilot, lambda: tree.region.bottom <= pane.region.y and
                    tree.region.width == 42, "the tree above the pane, the whole width")
        assert tree.region.x == pane.region.x == 0
        # each about half of what the detail line and the footer leave
        assert abs(tree.region.height - pane.region.height) <= 2
        await until(pilot, lambda: any(f"● {LONG} " in row for row in tree_rows(app)),
                    "the long name whole on its row")
        assert any("● ticker [ticker-1] running" in row for row in tree_rows(app))
        # the detail line above and the pane's own status line (its level, search) stay
        assert shown(app, app.detail_bar)
        assert shown(app, pane.query_one("#output-status"))
        assert app.detail_bar.region.bottom <= tree.region.y


async def test_a_wide_terminal_keeps_the_tree_beside_the_pane(tmp_path: Path) -> None:
    async with following(tmp_path / "run", launch_file(tmp_path), size=(120, 32),
                         name="long") as (app, pilot, _):
        tree, pane = app.launch_tree, app.output_panel
        await until(pilot, lambda: tree.region.right <= pane.region.x and tree.region.width
                    > 0, "the tree beside the pane")
        assert tree.region.y == pane.region.y and tree.region.width < 60
        # narrowed (a phone turned upright), then widened again: stacked, then beside
        await pilot.resize_terminal(42, 40)
        await until(pilot, lambda: tree.region.bottom <= pane.region.y and
                    tree.region.width == 42, "the tree above the pane at 42 columns")
        await pilot.resize_terminal(120, 32)
        await until(pilot, lambda: tree.region.right <= pane.region.x and
                    tree.region.y == pane.region.y and 0 < tree.region.width < 60,
                    "the tree beside the pane again at 120 columns")


@pytest.fixture
def browser_footer(monkeypatch: pytest.MonkeyPatch) -> None:
    """Footers as a browser tab's process makes them (serve_tab.py), for this test only."""
    for name in ("__init__", "compose", "DEFAULT_CSS"):
        monkeypatch.setattr(Footer, name, getattr(Footer, name))
    monkeypatch.setattr(Footer, "on_resize", None, raising=False)  # removed after
    compact_footers()
    phone_footers()


def footer_rows(app: TuiLaunchApp) -> list[list[str]]:
    """The footer's keys ("s Stop") on its rows as shown, left to right (rows scrolled out
    of its height left out)."""
    footer = app.screen.query_one(Footer)
    keys = [key for key in app.screen.query(FooterKey)
            if key.region.height and footer.region.contains_region(key.region)]
    rows: dict[int, list[FooterKey]] = {}
    for key in keys:
        rows.setdefault(key.region.y, []).append(key)
    return [[f"{k.key_display} {k.description}" for k in sorted(row, key=lambda k: k.region.x)]
            for _, row in sorted(rows.items())]


async def test_a_phones_footer_offers_the_nodes_keys(tmp_path: Path,
                                                      browser_footer: None) -> None:
    async with following(tmp_path / "run", launch_file(tmp_path), size=(42, 40),
                         name="long") as (app, pilot, _):
        await until(pilot, lambda: len(footer_rows(app)) == 2, "a footer of two rows")
        first, second = footer_rows(app)
        assert first == ["s Stop", "r Restart", "t Start", "^p palette"]
        assert second[:2] == ["i Type", "/ Search"]
        # a tablet's width: one row, in the order it had
        await pilot.resize_terminal(113, 40)
        await until(pilot, lambda: len(footer_rows(app)) == 1, "a footer of one row")
        keys = footer_rows(app)[0]
        assert keys[0] == "/ Search" and {"s Stop", "r Restart", "t Start"} <= set(keys)
