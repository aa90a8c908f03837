"""What the keyboard (keyboard.py's NodeKeyboard: `i`, `g`, `c`) needs of the one session it
acts on: its port and engine thread, its tree and selection, where its typing line goes,
and how a line is said. A session's view (session_view.py's SessionView) is the one such
host, the single TUI's as each of a fleet's, so both hold the same keyboard and a fleet
types into a node in its own screen, a browser's page too."""

from __future__ import annotations

from typing import Any, Protocol

from textual.app import App
from textual.notifications import SeverityLevel
from textual.widget import Widget

from ...client.port import LaunchPort
from ...engine.run.engine_thread import EngineThread
from ..screens.tree_panel import LaunchTree


class KeyboardHost(Protocol):
    """One session, as the keyboard acts on it. Read, never set, by the keyboard."""

    @property
    def app(self) -> App[Any]:
        """The app on screen: its workers, dialogs, focus and held keys (key_order.py)."""

    @property
    def supervisor(self) -> LaunchPort | None:
        """The session's client; None until it is followed."""

    @property
    def engine(self) -> EngineThread: ...

    @property
    def launch_tree(self) -> LaunchTree: ...

    @property
    def asked_to_stop(self) -> set[str]:
        """The stops this client asked for (a restart's): their exit is no failure."""

    @property
    def read_only(self) -> bool: ...

    @property
    def who(self) -> str:
        """The session a question names (a fleet's `nuc:base`; the single TUI's: '')."""

    def client(self) -> LaunchPort:
        """The session's client; SessionError (a LaunchError) while it is not followed."""

    def nodes_shown(self) -> bool:
        """Whether the Nodes tab (the trees) is on screen: the keyboard's keys are its."""

    def unavailable(self) -> str | None:
        """Why the session takes no keys now (not followed, out of reach); None: it does."""

    def selected_process(self) -> str | None:
        """The process of the session's selected row, when the row is a node."""

    def notify(self, message: str, *, severity: SeverityLevel = "information") -> None:
        """One line on screen (a fleet's names its session first)."""

    async def show_typing_line(self, line: Widget) -> None:
        """Puts the line taking the keys above the session's tree and pane."""

    def update_status(self) -> None: ...
