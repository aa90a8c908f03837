"""The one port to a launch: what a frontend (the TUI, a fleet's TUI, the command line's
end-of-run report) may ask of a running session and read of it. The session client
(remote_supervisor.RemoteSupervisor) implements it, for a session on this computer as over
an ssh link; frontends hold a `LaunchPort`, never the client's class, and probe nothing
(no isinstance, no getattr): what a session cannot do is an error it raises (SessionError,
or ReadOnlyError for a read-only view), said on screen in one line.

A Protocol rather than a base class: the client stays one object of its own, and mypy
checks that it has every member here where a frontend is handed one.
"""

from __future__ import annotations

from pathlib import Path
from typing import Literal, Protocol, TypeVar

from ..engine.plan.model import Plan, PlanDiff
from ..engine.run.events import Consumer, Event
from ..engine.run.vocabulary.request import Request
from ..engine.run.vocabulary.requests import Restart, Start, Stop

R = TypeVar("R")

Verb = Literal["stop", "restart", "start"]
"""An operator's command on one process (s, r, t; `tuilaunch stop|restart|start`)."""

VERBS: dict[Verb, type[Start | Stop | Restart]] = {"start": Start, "stop": Stop,
                                                   "restart": Restart}
"""Each command as the request that asks it."""


class LifecyclePort(Protocol):
    """The managed nodes' states as the session's events report them, and a transition
    asked of one (the session's server asks the node)."""

    states: dict[str, str]

    async def request(self, process: str, transition: str) -> bool: ...


class LaunchPort(Protocol):
    """A session followed by a frontend. States and events come from the session's server:
    `states` ({process: pending|running|stopping|exited|failed|respawning|skipped}), the
    events handed to `subscribe`d consumers while `run` runs, `history` (what happened
    before this frontend came)."""

    name: str
    host: str | None  # the machine the session runs on (None: this one)
    log_dir: Path  # the session's log folder, on its machine

    # what the events told (read-only: RemoteSupervisor's client/session_state.py keeps them)
    @property
    def states(self) -> dict[str, str]: ...

    @property
    def pids(self) -> dict[str, int]:
        """The running processes' pids."""
        ...

    @property
    def reasons(self) -> dict[str, str]:
        """How each process last ended ("exit code 1", "SIGSEGV")."""
        ...

    @property
    def crashed(self) -> dict[str, str]:
        """Ended with nobody asking: the run's exit status is 1."""
        ...

    @property
    def history(self) -> list[Event]: ...

    @property
    def lifecycle(self) -> LifecyclePort: ...

    @property
    def shutdown_reason(self) -> str | None:
        """Why it began to stop, as its server said (None: it did not)."""
        ...

    read_only: bool
    # how following it ended: left on purpose, lost, killed, or stopped (why)
    detached: bool
    lost: bool
    killed_server: bool
    # the ssh link, when one is between (host not None)
    # (read-only: a port's reconnector keeps them, engine/run/session/reconnector.py)
    @property
    def link_lost(self) -> str | None: ...

    @property
    def lost_reason(self) -> str | None: ...

    @property
    def attempt(self) -> int:
        """The reconnection's attempt under way, or the last one."""
        ...

    @property
    def attempt_since(self) -> float | None:
        """When the one under way began (monotonic; None: between)."""
        ...

    only: str | None  # the process whose lines the link carries (None: all)
    stamps_shown: bool

    def subscribe(self, consumer: Consumer) -> None: ...

    async def run(self, keep_alive: bool = True) -> int: ...

    async def command(self, verb: Verb, process: str) -> None: ...

    async def restart(self, process_id: str, prefix: str | None = None,
                      log_level: str | None = None, terminal: bool = False) -> None: ...

    async def run_action(self, action_id: str) -> None: ...

    async def replace_plan(self, plan: Plan) -> PlanDiff: ...

    async def request(self, request: Request[R]) -> R:
        """Any request of the protocol (vocabulary/requests.py), its reply as the request
        reads it; SessionError with the server's words when refused."""
        ...

    async def show(self, process: str | None) -> None: ...

    async def read_stamps(self, shown: bool, since: int | None,
                          ) -> tuple[int, int, dict[int, int]]: ...

    async def shutdown(self, reason: str = "shutdown") -> None: ...

    async def detach(self) -> None: ...

    def kill_all(self) -> None: ...

    def silent_for(self) -> float: ...

    def retry_now(self) -> None: ...

