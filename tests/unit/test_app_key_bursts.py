"""Keys go where they are typed, over an in-memory session (moved from tests/integration/
test_tui_keys.py, which keeps what a real terminal parses): a burst read in one go (over ssh,
pasted, sent by tmux) after a key that opens a field reaches that field, in order, and never
the tree's keys (`s` stops a node); the focus is always somewhere visible; dialogs do not
stack."""

from __future__ import annotations

import sys
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from textual import events
from textual.pilot import Pilot
from textual.widgets import Input

from tests.unit.memory_port import MemoryPort
from tests.unit.pilot_sessions import burst, dialogs, keys_handled, launch_file, shown
from tests.unit.test_app_pilot import select, until
from tuilaunch.engine.run.events import Output
from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.fields import Field

TWO = f"""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('robot', default_value='r1', description='the robot'),
        ExecuteProcess(name='lines', cmd=[{sys.executable!r}, 'line_reader.py'],
                       output='screen', emulate_tty=True),
        ExecuteProcess(name='quiet', cmd=['sleep', '600']),
    ])
"""

COMMANDS = {"stop", "restart", "start", "shutdown"}
"""What a key typed into a field must never ask of the session."""


@asynccontextmanager
async def two_started(tmp_path: Path) -> AsyncIterator[tuple[TuiLaunchApp, Pilot[int],
                                                             MemoryPort]]:
    """The TUI of TWO at 80x24, both processes started, lines-1 having said `ready`, and
    quiet-2 selected."""
    async with shown(tmp_path, launch_file(tmp_path, TWO), name="two") as (app, pilot, port):
        port.tell(Output("lines-1", stream="stdout", lines=["ready"]))
        await until(pilot, lambda: "ready" in app.store.text(View("lines-1")), "ready said")
        select(app, "quiet-2")
        await pilot.pause()
        yield app, pilot, port


def field(app: TuiLaunchApp, field_id: str) -> Field:
    return app.query_one(f"#{field_id}", Field)


def typed(app: TuiLaunchApp, field_id: str) -> str | None:
    """What a field holds; None while it is not there (a tab's panel is made the first
    time the tab shows)."""
    found = app.query(f"#{field_id}")
    return str(found.first(Field).value) if found else None


def palette_input(app: Any) -> str | None:
    """What the command palette's input holds; None before the palette has laid it out."""
    found = app.screen.query("CommandInput")
    return str(found.first().value) if found else None


async def test_a_search_typed_in_one_burst_is_searched_and_never_stops_the_node(
        tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, port):
        # `/set`, `/rst` and `\st` each as one read: search / filter text, no s, r, t
        burst(app, "slash", *"set")
        await until(pilot, lambda: field(app, "search-input").value == "set", "/set typed")
        assert app.focused is field(app, "search-input")
        burst(app, "enter", "slash", *"rst", "enter")
        await until(pilot, lambda: app.output_panel.search == "rst", "/rst searched")
        burst(app, "backslash", *"st")
        await until(pilot, lambda: field(app, "filter-input").value == "st", "\\st typed")
        burst(app, "escape")
        await keys_handled(pilot, app)
        assert not COMMANDS & set(port.ops())  # nothing stopped, restarted or started


async def test_keys_after_i_reach_the_node_in_order(tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, port):
        port.answers["status"] = lambda **_: {"processes": [
            {"id": "lines-1", "state": "running", "terminal": True}]}
        select(app, "lines-1")
        await pilot.pause()
        # i, then a line with s, r, t, q and a digit in it, Enter: one read
        burst(app, "i", *"start 1 q", "enter")
        await until(pilot, lambda: "".join(f["data"] for op, f in port.asked
                                           if op == "input") == "start 1 q\r",
                    "the line sent to the node, in order")
        assert app.keyboard.typing_to == "lines-1" and not app.quitting
        assert ("typing", {"process": "lines-1", "on": True}) in port.asked
        assert not COMMANDS & set(port.ops())
        burst(app, "ctrl+right_square_bracket", "q")  # the keys are back: q asks to quit
        await until(pilot, lambda: dialogs(app) == ["QuitScreen"], "the quit question")
        burst(app, "n")
        await until(pilot, lambda: dialogs(app) == [], "answered")


async def test_the_palette_and_a_field_opened_by_a_tab_key_get_the_burst(
        tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, port):
        # ctrl+p and a command's words in one read: the words are in the palette's input
        burst(app, "ctrl+p", *"stop")
        await until(pilot, lambda: palette_input(app) == "stop", "stop in the palette")
        burst(app, "escape")
        await until(pilot, lambda: dialogs(app) == [], "the palette closed")
        # `:` opens the palette too (as in vim, k9s)
        burst(app, "colon", *"rst")
        await until(pilot, lambda: palette_input(app) == "rst", "rst in the palette")
        burst(app, "escape")
        await until(pilot, lambda: dialogs(app) == [], "the palette closed")
        # the Topics tab and its filter, in one read with the text
        burst(app, "5", "slash", *"chat")
        await until(pilot, lambda: typed(app, "tpc-filter") == "chat", "chat filtered")
        assert not COMMANDS & set(port.ops())


async def test_a_value_typed_after_the_args_tab_key_in_one_read_goes_into_its_field(
        tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, port):
        # the Args tab, one tab past Apply and Defaults into the robot's field, its value
        # replaced: one read
        burst(app, "2", "tab", "ctrl+u", *"r2sq")
        await until(pilot, lambda: field(app, "arg-robot").value == "r2sq", "r2sq typed")
        assert not app.quitting and not COMMANDS & set(port.ops())
        await until(pilot, lambda: app.args_tab.preview is not None
                    and app.args_tab.preview.arguments.get("robot") == "r2sq", "previewed")
        # back to Apply (shift+tab from the first value), right to Defaults: a space there
        # resets nothing, Enter does
        burst(app, "shift+tab", "right", "space")
        await until(pilot, lambda: app.focused is app.query_one("#defaults"), "on Defaults")
        await keys_handled(pilot, app)
        assert field(app, "arg-robot").value == "r2sq"
        burst(app, "enter")
        await until(pilot, lambda: field(app, "arg-robot").value == "r1", "the default back")


# --- focus and dialogs: the habits of a keyboard user -------------------------------------


async def test_ctrl_c_twice_asks_once_and_n_leaves_no_question(tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, port):
        burst(app, "ctrl+c", "ctrl+c")
        await until(pilot, lambda: dialogs(app) == ["QuitScreen"], "one question")
        burst(app, "q", "ctrl+c")
        await keys_handled(pilot, app)
        assert dialogs(app) == ["QuitScreen"]
        burst(app, "n")
        await until(pilot, lambda: dialogs(app) == [], "no question left")
        assert not COMMANDS & set(port.ops())


async def test_tab_keys_and_q_work_from_every_tab_and_the_focus_is_never_a_field(
        tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, _port):
        for key, tab in (("2", "args"), ("3", "services"), ("4", "params"), ("5", "topics"),
                         ("1", "nodes")):
            burst(app, key, "q")  # the tab, then q at once: the quit question, nothing typed
            await until(pilot, lambda: dialogs(app) == ["QuitScreen"], f"{key}: asked")
            assert app.tabs.active == tab
            burst(app, "n")
            await until(pilot, lambda: dialogs(app) == [], "answered")
            assert not isinstance(app.focused, Input), (tab, app.focused)
            assert app.focused is not None and app.focused.has_pseudo_class("focus")
        assert field(app, "arg-robot").value == "r1"  # no q, no digit typed into it
        # each tab's list has its filter one `/` away, and esc comes back to the list
        burst(app, "3", "slash", *"srv")
        await until(pilot, lambda: typed(app, "svc-filter") == "srv", "srv filtered")
        burst(app, "escape", "q")
        await until(pilot, lambda: dialogs(app) == ["QuitScreen"], "asked from the list")
        burst(app, "n")
        await until(pilot, lambda: dialogs(app) == [], "answered")
        assert app.focused is app.query_one("#svc-list")


async def test_leaving_the_search_goes_back_where_it_was_typed(tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, _port):
        tree = app.launch_tree
        burst(app, "slash", *"abc", "escape")  # from the tree: back to the tree
        await until(pilot, lambda: app.focused is tree, "back on the tree")
        burst(app, "backslash", *"ready", "enter")
        await until(pilot, lambda: app.output_panel.view.text == "ready", "filtered")
        assert app.focused is tree
        lines = app.output_panel.line_view
        app.screen.set_focus(lines)
        burst(app, "slash", *"x", "enter")  # from the pane: back to the pane
        await until(pilot, lambda: app.output_panel.search == "x", "searched")
        assert app.focused is lines


async def test_f1_and_the_palettes_keys_show_the_keys_and_esc_closes_them(
        tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, _port):
        burst(app, "f1")
        await until(pilot, lambda: dialogs(app) == ["HelpScreen"], "the keys")
        burst(app, "escape")
        await until(pilot, lambda: dialogs(app) == [], "closed")
        burst(app, "ctrl+p", *"keys")
        await until(pilot, lambda: dialogs(app) == ["CommandPalette"]
                    and palette_input(app) == "keys", "keys in the palette")
        await until(pilot, lambda: "Keys" in str(app.screen.query_one("CommandList")
                                                  .get_option_at_index(0).prompt),
                    "Keys offered first")
        burst(app, "enter")
        await until(pilot, lambda: dialogs(app) == ["HelpScreen"], "the keys")
        assert not app.query("HelpPanel")  # not Textual's side panel (30 of 80 columns)
        burst(app, "escape")
        await until(pilot, lambda: dialogs(app) == [], "closed")


async def test_a_paste_right_after_slash_is_searched(tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, port):
        burst(app, "slash")  # `/`, then a bracketed paste, in one read
        app.post_message(events.Paste("start"))
        burst(app, "enter")
        await until(pilot, lambda: app.output_panel.search == "start", "start searched")
        assert not COMMANDS & set(port.ops())


async def test_the_footer_does_not_offer_keys_a_field_types(tmp_path: Path) -> None:
    async with two_started(tmp_path) as (app, pilot, _port):
        offered = {b.binding.description for b in app.screen.active_bindings.values()
                   if b.binding.show}
        assert {"Search", "Filter"} <= offered  # in the tree: / and \ are commands
        burst(app, "slash")
        await until(pilot, lambda: app.focused is field(app, "search-input"), "searching")
        offered = {b.binding.description for b in app.screen.active_bindings.values()
                   if b.binding.show}
        assert not {"Search", "Filter", "Level", "Quit"} & offered  # typed into the field


async def test_c_then_y_in_one_read_copies_the_command_line(tmp_path: Path) -> None:
    command = f"{sys.executable} line_reader.py"
    async with two_started(tmp_path) as (app, pilot, port):
        port.answers["status"] = lambda **_: {"processes": [
            {"id": "lines-1", "state": "running", "command_line": command}]}
        select(app, "lines-1")
        await pilot.pause()
        burst(app, "c", "y")  # the dialog comes after a round trip: y waits for it
        await until(pilot, lambda: "line_reader.py" in app.clipboard, "copied")
        await until(pilot, lambda: dialogs(app) == [], "y copied and closed it")
