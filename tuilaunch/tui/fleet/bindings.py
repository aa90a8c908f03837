"""The fleet view's keys (tui/fleet/app.py's bindings) and its help screen listing them.

The tree's commands, the pane's keys and the tabs' are the single TUI's pieces (nodes/,
screens/); these say which key reaches which, in a fleet of several sessions.
"""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import VerticalScroll
from textual.widgets import Static

from ..inspect.inspector import INSPECTOR_BINDINGS
from ..keys.keyboard import KEYBOARD_BINDINGS
from ..screens.dialogs import HelpScreen
from ..screens.output_panel import PANE_BINDINGS
from ..session_view import COMMAND_BINDINGS, lifecycle_bindings

BINDINGS: list[BindingType] = [
    *KEYBOARD_BINDINGS,  # i, g, c: the selected session's keyboard (FleetApp.action_keyboard)
    Binding("1", "tab('nodes')", "Nodes",
            tooltip="The sessions' trees and the selected node's output"),
    Binding("2", "tab('args')", "Args",
            tooltip="The selected session's launch arguments: edit, F5 applies"),
    Binding("3", "tab('services')", "Services",
            tooltip="The selected session's services: call one"),
    Binding("4", "tab('params')", "Params",
            tooltip="The selected session's nodes' parameters: get and set them"),
    Binding("5", "tab('topics')", "Topics", show=False,
            tooltip="The selected session's topics, rates and QoS, echo"),
    *COMMAND_BINDINGS,  # the selected session's view's (FleetApp.action_command)
    *PANE_BINDINGS,  # the single TUI's pane keys, on the selected session's pane
    Binding("right_curly_bracket", "jump(1)", "Next session", show=False,
            tooltip="The next session's root (as k9s switches context)"),
    Binding("left_curly_bracket", "jump(-1)", "Previous session", show=False,
            tooltip="The previous session's root"),
    Binding("a", "all_output", "All", show=False, tooltip="This session's every node"),
    *lifecycle_bindings(show=False),
    *INSPECTOR_BINDINGS,  # o, L, b: on the selected session (FleetApp.action_inspector)
    # not in the footer: the header says it (`O: this one in full`), and the single TUI's
    # keys come first there (a tablet's browser shows Type to Filter whole)
    Binding("O", "open_session", "Open", show=False,
            tooltip="The selected session in the single-session TUI, with every key of "
            "one session (d there comes back)"),
    Binding("f5", "apply", "Apply", show=False,
            tooltip="Relaunch the selected session with the edited arguments and its "
            "file as it is now"),
    Binding("R", "reconnect", "Reconnect", show=False,
            tooltip="Try the selected session's link again now"),
    Binding("question_mark,f1", "help", "Help", tooltip="These keys"),
    Binding("q", "quit_fleet", "Quit (detach)",
            tooltip="Leave: every session runs on (tuilaunch stop stops them)"),
    Binding("ctrl+c", "quit_fleet", "Quit", show=False, priority=True),
]


class FleetHelp(HelpScreen):
    """The fleet's keys (its bindings, with what each does), over the screen."""

    def compose(self) -> ComposeResult:
        rows = ["One TUI over several sessions: a tree per session; the keys act on the",
                "session of the selected row. up/down cross from one session's tree to the",
                "next and stop at the ends; } and { jump to a session's root. s and r on more",
                "than one running node ask first, naming the session.", ""]
        for binding in BINDINGS:
            assert isinstance(binding, Binding)
            if not binding.description:
                continue  # a key's stand-in where it cannot act (keyboard.py's i, g)
            keys = binding.key.replace("backslash", "\\").replace("slash", "/").replace(
                "question_mark", "?").replace("right_square_bracket", "]").replace(
                "left_square_bracket", "[").replace(",", ", ")
            keys = keys.replace("right_curly_bracket", "}").replace(
                "left_curly_bracket", "{").replace("less_than_sign", "<").replace(
                "greater_than_sign", ">")
            rows.append(f"  {keys:<9} {binding.tooltip or binding.description}")
        with VerticalScroll():
            yield Static("\n".join(rows))
