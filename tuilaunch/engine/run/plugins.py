"""How layers above `run` (the ROS integration in `engine/ros`) plug into a launch.

`run` knows processes, output, triggers and signals, and nothing of ROS. What needs ROS
(lifecycle nodes, component loading, the launch's service calls) is a plugin handed to the
`Supervisor` when it is made (`Supervisor(..., plugins=[...])` or `add_plugin`, before
`run`). A plugin implements any of the hooks below; `Plugin` gives do-nothing defaults, so a
plugin only writes the hooks it needs. A plugin reports through the supervisor's public
`emit(Event(...))` and reads its public `plan`, `states` and `shutting_down`.

The session server takes the same plugins' `handlers()`: the requests clients can send, by
their class (vocabulary/requests.py: `{"op": "lifecycle", ...}` is a `LifecycleState`), each
an async function of the decoded request and the asking client whose return value is the
reply's result. A handler raises `LaunchError`, `ValueError` or `TypeError` for a request
the client got wrong (the reply carries the message).

Streams for one client (a topic's echo, the rates it watches): a handler is handed the
asking connection's id (the server's, whatever the client sent); `serve(clients)` hands
the plugin the server's `Clients`, whose `send` reaches one client or all, and
`client_gone(id)` says a connection closed, so its streams can stop. Events sent that way
are neither logged nor kept for late clients (a rate a second would crowd out the state
changes a late client needs).
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Mapping
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

if TYPE_CHECKING:
    from ..plan.model import ActionPlan, ProcessPlan
    from .events import Event
    from .vocabulary.request import Request

ActionRunner = Callable[["ActionPlan"], Awaitable[bool]]
"""Performs one action of the plan; True when it succeeded (the action is then `done`)."""

Handler = Callable[[Any, int], Awaitable[Any]]
"""Answers one request of a session client: the decoded request (of the class it is
registered for) and the client's id in, the result out."""

Handlers = Mapping[type["Request[Any]"], Handler]
"""A plugin's requests: the handler of each request class."""


class Clients(Protocol):
    """The session server's clients, as a plugin reaches them (handed over by `serve`)."""

    def send(self, event: Event, client: int | None = None) -> None:
        """To the subscribed client `client` (a request's `"client"`), or to every subscribed
        client (None); a client that did not subscribe gets nothing."""
        ...

    def subscribed(self, client: int) -> bool:
        """Whether that client is connected and receives events."""
        ...


@runtime_checkable
class SupervisorPlugin(Protocol):
    """The hooks the supervisor calls, all on its event loop."""

    detached_actions: frozenset[str]
    """Action kinds a shutdown does not wait for while they run (a service call waiting for
    a service that will never come up must not hold the launch open)."""

    def actions(self) -> Mapping[str, ActionRunner]:
        """Action kinds of the plan this plugin performs (`call_service`, ...)."""
        ...

    def run_started(self) -> Awaitable[Any] | None:
        """The run begins (before any process starts); the awaitable returned, if any,
        runs as a task of the launch."""
        ...

    def process_started(self, proc: ProcessPlan) -> Awaitable[Any] | None:
        """A process of the launch has just started; the awaitable returned, if any, runs
        as a task of the launch (cancelled when the run ends)."""
        ...

    def process_exited(self, process_id: str) -> None:
        """A process of the launch has exited (before its `exited` event is sent)."""
        ...

    async def close(self) -> None:
        """The run is over: release what the plugin holds (a ROS node, subscriptions)."""
        ...

    def handlers(self, find_process: Callable[[str], str]) -> Handlers:
        """Session requests this plugin answers, by class. `find_process` turns what a
        client typed (id, node name) into a process id, or raises LaunchError."""
        ...

    def snapshot(self) -> dict[str, Any]:
        """What a session client gets when it subscribes, beside the process states (the
        lifecycle states so far, ...): keys of the subscribe reply."""
        ...

    def serve(self, clients: Clients) -> None:
        """A session server serves this launch: `clients` reaches its clients (called once,
        before any request)."""
        ...

    def client_gone(self, client: int) -> None:
        """The session client with this id disconnected: stop what it asked for."""
        ...


class Plugin:
    """A base with every hook doing nothing: subclass it and override what you need."""

    detached_actions: frozenset[str] = frozenset()

    def actions(self) -> Mapping[str, ActionRunner]:
        return {}

    def run_started(self) -> Awaitable[Any] | None:
        return None

    def process_started(self, proc: ProcessPlan) -> Awaitable[Any] | None:
        return None

    def process_exited(self, process_id: str) -> None:
        return None

    async def close(self) -> None:
        return None

    def handlers(self, find_process: Callable[[str], str]) -> Handlers:
        return {}

    def snapshot(self) -> dict[str, Any]:
        return {}

    def serve(self, clients: Clients) -> None:
        return None

    def client_gone(self, client: int) -> None:
        return None


__all__ = ["ActionRunner", "Clients", "Handler", "Handlers", "Plugin", "SupervisorPlugin"]
