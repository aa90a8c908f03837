"""What the selection's commands (commands.py) need of the session they act on: its view
(session_view.py's SessionView), the single TUI's one as each of a fleet's."""

from __future__ import annotations

from typing import Protocol

from ...client.port import LaunchPort
from ...engine.plan.session import Session
from ...engine.run.engine_thread import EngineThread


class SessionParts(Protocol):
    """The session's client (None until it is followed), the engine thread its calls run
    on, and the session (its plan): what each of the view's tabs acts through."""

    # read, never set, by the tabs: properties, so the view's own attributes fit
    @property
    def engine(self) -> EngineThread: ...
    @property
    def supervisor(self) -> LaunchPort | None: ...
    @property
    def session(self) -> Session: ...


class NodesHost(SessionParts, Protocol):
    """The session's parts, and the stops it asked for (their non-zero exit is no failure)."""

    @property
    def asked_to_stop(self) -> set[str]: ...
