"""An XML launch file in the TUI: the same tree, argument form, preview and restart."""

from __future__ import annotations

from textual.widgets import Checkbox, Input, Select

from tuilaunch.tui.screens.args_panel import ArgsPanel

from ..conftest import EXAMPLES
from .test_tui import pids, row_text, states, tui, until

XML_BRINGUP = str(EXAMPLES / "launch" / "bringup.launch.xml")


async def test_xml_bringup_tree_form_preview_and_apply(tmp_path):
    async with tui(tmp_path, "robot:=xtui", path=XML_BRINGUP) as (app, pilot):
        await until(pilot, lambda: states(app).get("listener-2") == "running"
                    and states(app).get("talker-1") == "running")
        assert "skipped" in row_text(app, "talker-5")  # the YAML include waits on listener
        talker_pid = pids(app)["talker-1"]
        await pilot.press("2")
        form = app.query_one(ArgsPanel)
        assert isinstance(form.query_one("#arg-mode"), Select)
        rate = form.query_one("#arg-rate", Input)  # a float argument: a word is warned of
        typed = rate.value
        rate.value = "fast"
        await pilot.pause()
        assert "Warning: argument 'rate' = 'fast' is not a number" in str(
            app.query_one("#args-preview").render())
        rate.value = typed
        form.query_one("#arg-listener", Checkbox).value = False
        await pilot.pause()
        preview = str(app.query_one("#args-preview").render())
        assert "would stop: listener-2" in preview and "talker-5" in preview
        assert states(app)["listener-2"] == "running"  # nothing changes before applying
        await pilot.press("f5")
        await until(pilot, lambda: states(app)["listener-2"] == "skipped"
                    and states(app).get("listener-6") == "running")
        assert pids(app)["talker-1"] == talker_pid  # the talker's command line is unchanged
        assert app.session.arguments["listener"] == "false"
