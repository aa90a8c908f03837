"""A fleet's session as the host of the single TUI's pieces: its Args tab (arguments.py's
ArgsHost), its tree's commands (nodes/host.py's NodesHost) and its keyboard
(keyboard_host.py's KeyboardHost: `i`, `g`, `c` on its nodes, in the fleet's own screen).
"""

from __future__ import annotations

from typing import Any, Protocol

from textual.app import App
from textual.notifications import SeverityLevel
from textual.widget import Widget
from textual.widgets import TabbedContent

from ...client.port import LaunchPort
from ...engine.plan.session import Session
from ...engine.run.engine_thread import EngineThread
from ...engine.run.session.session_dir import SessionError
from ..screens.tree_panel import LaunchTree, RowKind
from .member import Member


class FleetScreen(Protocol):
    """What a member's host needs of the fleet's app (app.py's FleetApp)."""

    # read, never set, here: properties, so the app's own attributes (a LaunchTabs) fit
    @property
    def engine(self) -> EngineThread: ...
    @property
    def read_only(self) -> bool: ...
    @property
    def tabs(self) -> TabbedContent: ...
    @property
    def nodes_tab(self) -> Widget:
        """The Nodes tab's column: a typing line goes in it, above the trees and panes."""

    def update_status(self) -> None: ...


class MemberHost:
    """A member as the host of the single TUI's pieces: its session, its link, its tree,
    the stops it asked; the app's engine thread, header and screen. What it says names
    the session (`nuc:base: ...`)."""

    quitting = False
    """A fleet view never stops its sessions by leaving."""

    def __init__(self, member: Member, fleet: FleetScreen) -> None:
        self.member = member
        self.fleet = fleet
        self.own_relaunch: list[str] | None = None

    @property
    def app(self) -> App[Any]:
        return self.member.tree.app

    @property
    def who(self) -> str:
        return self.member.label

    @property
    def session(self) -> Session:
        return self.member.session

    @property
    def supervisor(self) -> LaunchPort | None:
        return self.member.supervisor

    @property
    def engine(self) -> EngineThread:
        return self.fleet.engine

    @property
    def launch_tree(self) -> LaunchTree:
        return self.member.tree

    @property
    def asked_to_stop(self) -> set[str]:
        return self.member.asked_to_stop

    @property
    def read_only(self) -> bool:
        return self.fleet.read_only

    def client(self) -> LaunchPort:
        if self.member.supervisor is None:
            raise SessionError(self.member.problem or "not connected")
        return self.member.supervisor

    def over_link(self) -> LaunchPort | None:
        supervisor = self.member.supervisor
        return supervisor if supervisor is not None and supervisor.host is not None else None

    def nodes_shown(self) -> bool:
        return self.fleet.tabs.active == "nodes"

    def unavailable(self) -> str | None:
        why = self.member.unavailable()
        if why is None:
            return None
        return "the session ended" if self.member.ended else \
            f"{why}; its nodes take no keys until it is back"

    def selected_process(self) -> str | None:
        node = self.member.tree.cursor_node
        if node is None or node.data is None or node.data.kind != RowKind.PROCESS:
            return None
        return node.data.ref

    def notify(self, message: str, *, severity: SeverityLevel = "information",
               title: str = "") -> None:
        self.app.notify(f"{self.member.label}: {message}", severity=severity, title=title)

    async def show_typing_line(self, line: Widget) -> None:
        await self.fleet.nodes_tab.mount(line, before="#fleet-split")

    def update_status(self) -> None:
        self.fleet.update_status()

    def drain(self) -> None:
        self.member.show_events(self.member.buffer.drain())

    def describe_waiting(self) -> None:
        self.member.refresh_root()  # the new plan's counts
