"""What the selection's commands (commands.py) need of the session they act on: its view
(session_view.py's SessionView), the single TUI's one as each of a fleet's."""

from __future__ import annotations

from typing import Protocol

from ...client.port import LaunchPort
from ...engine.plan.session import Session
from ...engine.run.engine_thread import EngineThread


class NodesHost(Protocol):
    """The session's client (None until it is followed), the engine thread its calls run
    on, the session (its plan), and the stops it asked for (their non-zero exit is no
    failure)."""

    # read, never set, by the commands: properties, so the view's own attributes fit
    @property
    def engine(self) -> EngineThread: ...
    @property
    def supervisor(self) -> LaunchPort | None: ...
    @property
    def session(self) -> Session: ...
    @property
    def asked_to_stop(self) -> set[str]: ...
