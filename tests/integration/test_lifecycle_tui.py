"""The tree shows lifecycle states live and components with their load results; keys and
palette commands drive lifecycle transitions. Real rclpy nodes, real container."""

from __future__ import annotations

from pathlib import Path

from tuilaunch.tui.screens.tree_panel import LaunchTree

from .test_composition import CONTAINER, composition_interfaces, with_interfaces  # noqa: F401
from .test_tui import row_text, tui, until

LIFECYCLE = """
from launch import LaunchDescription
from launch_ros.actions import LifecycleNode

def generate_launch_description():
    return LaunchDescription([
        LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker', name='lc',
                      namespace='', autostart=True, parameters=[{'rate': 2.0}])])
"""


async def test_lifecycle_state_is_live_and_keys_step_it(tmp_path: Path):
    path = tmp_path / "lc_launch.py"
    path.write_text(LIFECYCLE)
    async with tui(tmp_path, path=str(path)) as (app, pilot):
        await until(pilot, lambda: "· active" in row_text(app, "lc-1"))
        tree = app.query_one(LaunchTree)
        tree.move_cursor(tree.rows["lc-1"])
        await pilot.pause()
        await pilot.press("left_square_bracket")  # down: deactivate
        await until(pilot, lambda: "· inactive" in row_text(app, "lc-1"))
        await pilot.press("left_square_bracket")  # down: clean up
        await until(pilot, lambda: "· unconfigured" in row_text(app, "lc-1"))
        # nothing below unconfigured: the key does not apply
        assert app.check_action("command", ("lifecycle", "down")) is None
        await pilot.press("right_square_bracket", "right_square_bracket")
        await until(pilot, lambda: "· active" in row_text(app, "lc-1"))
        commands = [c.title for c in app.get_system_commands(app.screen)]
        assert "Lifecycle: deactivate lc-1" in commands
        assert "Lifecycle: active shutdown lc-1" in commands
        assert "Lifecycle: configure lc-1" not in commands


async def test_components_show_their_load_result_under_the_container(
        tmp_path: Path, composition_interfaces: str, monkeypatch):  # noqa: F811
    monkeypatch.setenv("PYTHONPATH", with_interfaces(composition_interfaces)["PYTHONPATH"])
    path = tmp_path / "container_launch.py"
    path.write_text(CONTAINER)
    async with tui(tmp_path, path=str(path)) as (app, pilot):
        tree = app.query_one(LaunchTree)

        def label(ref: str) -> str:
            return str(tree.component_rows[ref].label)

        await until(pilot, lambda: "loaded" in label("box-1.1") and "failed" in label(
            "box-1.2") and "loaded" in label("load_components-1.1"))
        assert label("box-1.1") == "✓ /talker_c (tuilaunch_demos::Talker) loaded id 1"
        assert "Failed to find class with the requested plugin name." in label("box-1.2")
        assert tree.component_rows["box-1.1"].parent is tree.rows["box-1"]
        assert tree.component_rows["load_components-1.1"].parent is \
            tree.rows["load_components-1"]
