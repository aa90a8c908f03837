"""What the Nodes tab needs of whoever holds the session's link: the app (the single TUI)."""

from __future__ import annotations

from typing import Protocol

from ...client.port import LaunchPort
from ...engine.plan.session import Session
from ...engine.run.engine_thread import EngineThread


class NodesHost(Protocol):
    """The session's client (None until it is followed), the engine thread its calls run
    on, the session (its plan), whether this client is stopping the launch, and the stops it
    asked for (their non-zero exit is no failure)."""

    # read, never set, by the tab: properties, so a fleet's session can be a host too
    @property
    def engine(self) -> EngineThread: ...
    @property
    def supervisor(self) -> LaunchPort | None: ...
    @property
    def session(self) -> Session: ...
    @property
    def quitting(self) -> bool: ...
    @property
    def asked_to_stop(self) -> set[str]: ...

    def over_link(self) -> LaunchPort | None:
        """The client, when an ssh link is between (what crosses it is kept small)."""

    def drain(self) -> None:
        """Takes the events waiting now, for the tab (as a message)."""
