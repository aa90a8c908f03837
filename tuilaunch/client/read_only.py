"""A read-only client of a session: a view for a screen on the wall (`tuilaunch serve
--read-only`, `tuilaunch attach --read-only`).

Read-only is a property of the client, not of the keys: every request that would change
the launch or a node (stop, start, restart, relaunch, an action run again, a lifecycle
transition, typing into a node, a logger level, a params file loaded; and through the ROS
bridge, a parameter set or a service called) is refused here, before anything is sent,
with one line that says what was refused. The TUI shows that line where it shows any
failed command, so it needs no key of its own to be guarded. What only reads (status, the
logs, rates, echo, parameters listed) goes through as ever.
"""

from __future__ import annotations

from typing import Any

from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary.request import Request

REFUSED_BRIDGE: dict[str, str] = {
    "set_parameters": "setting a parameter",
    "call_service": "calling a service",
    "call_typed": "calling a service",
    "load_params": "loading parameters",
    "set_logger_level": "setting a logger level",
}
"""The ROS bridge's calls that change a node, for a TUI that holds a bridge of its own
(the Params and Services tabs of a session's TUI ask the session instead: a request's
`changes`)."""


class ReadOnlyError(SessionError):
    """A change refused by a read-only client: one line for the TUI to show."""


def refusal(what: str) -> ReadOnlyError:
    return ReadOnlyError(f"read-only view: {what} is refused")


def check_request(request: Request[Any]) -> None:
    """Raises ReadOnlyError for a session request that changes something: its class says
    how the refusal names it (`changes`, vocabulary/requests.py); the others only read
    (status, subscribe, view, read_log, topics, echo, ...)."""
    if request.changes is not None:
        raise refusal(request.changes)


class ReadOnlyBridge:
    """A ROS bridge whose calls that change a node are refused; the rest are the bridge's."""

    def __init__(self, bridge: Any) -> None:
        self._bridge = bridge

    def __getattr__(self, name: str) -> Any:
        what = REFUSED_BRIDGE.get(name)
        if what is not None:
            async def refused(*args: Any, **kwargs: Any) -> Any:
                raise refusal(what)

            return refused
        return getattr(self._bridge, name)


__all__ = ["ReadOnlyBridge", "ReadOnlyError", "check_request", "refusal"]
