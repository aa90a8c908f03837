"""Actions that do something once the launch runs: log lines, service calls, parameter
sets, timers, shutdown, emitted events (EmitEvent), stopping a process, and the Python
functions (OpaqueFunction) run with the launch context."""

from __future__ import annotations

import inspect
import signal
from collections.abc import Callable, Iterable
from typing import Any

from ...errors import DslError, caller_origin
from ..conditions import Condition
from ..substitutions import SubValue
from .base import Entity, entity_list


class LogInfo(Entity):
    def __init__(self, *, msg: SubValue, condition: Condition | None = None, **_: Any) -> None:
        self._init_entity(condition)
        self.msg = msg


class CallService(Entity):
    """`sl.call_service`: wait for a service, call it with a request built from a dict."""

    def __init__(self, server: SubValue, request: dict[str, Any] | None, verbosity: SubValue)\
            -> None:
        self._init_entity(None)
        self.server = server
        self.request = request or {}
        self.verbosity = verbosity


class SetParameters(Entity):
    """`sl.set_parameters`: wait for a node, set parameters through its service."""

    def __init__(self, node_name: SubValue, parameters: dict[str, Any], verbosity: SubValue)\
            -> None:
        self._init_entity(None)
        self.node_name = node_name
        self.parameters = dict(parameters)
        self.verbosity = verbosity


class TimerAction(Entity):
    def __init__(self, *, period: Any, actions: Iterable[Any],
                 condition: Condition | None = None, **_: Any) -> None:
        # launch_ros's RosTimer counts ROS time; tuilaunch counts wall time for both
        self._init_entity(condition)
        self.period = period
        self.actions = entity_list(list(actions))


class Shutdown(Entity):
    """An action that ends the whole launch (also `EmitEvent(event=Shutdown())`)."""

    def __init__(self, *, reason: SubValue = "reason not given", condition: Condition | None
                 = None, **_: Any) -> None:
        self._init_entity(condition)
        self.reason = reason
        self.emitted = False
        """EmitEvent(event=Shutdown()): launch's Shutdown action says `process[x] was
        required` when a process's exit runs it; the bare event says nothing."""


EMITTED_EVENTS: dict[type, Callable[[Any, Condition | None], Entity]] = {}
"""Event class -> the entity that performs `EmitEvent(event=...)`; one line per event kind."""


def EmitEvent(*, event: Any, condition: Condition | None = None, **_: Any) -> Entity:
    if isinstance(event, Shutdown):
        event.condition = condition
        event.emitted = True
        event.origin = caller_origin()
        return event
    for kind, make in EMITTED_EVENTS.items():
        if isinstance(event, kind):
            entity = make(event, condition)
            entity.origin = caller_origin()
            return entity
    raise DslError(f"tuilaunch does not support EmitEvent({type(event).__name__}) yet",
                   caller_origin())


class ActionMatcher:
    """launch.events.matches_action(action): picks the process an event is about."""

    def __init__(self, action: Any) -> None:
        self.target = action

    def __call__(self, candidate: Any) -> bool:
        return candidate is self.target


def matches_action(target_action: Any) -> ActionMatcher:
    return ActionMatcher(target_action)


class ShutdownProcess:
    """launch.events.process.ShutdownProcess: stop one process (SIGINT, then escalate)."""

    def __init__(self, *, process_matcher: Any) -> None:
        self.process_matcher = process_matcher


class StopProcess(Entity):
    """What EmitEvent(ShutdownProcess(...)) does: stop the matched process."""

    def __init__(self, target: Any, condition: Condition | None = None) -> None:
        self._init_entity(condition)
        self.target = target


EMITTED_EVENTS[ShutdownProcess] = lambda event, condition: StopProcess(
    getattr(event.process_matcher, "target", None), condition)


class SignalProcess:
    """launch.events.process.SignalProcess: one signal to one process (launch's own stop
    emits it: SIGINT, then SIGTERM and 'SIGKILL' on timers)."""

    def __init__(self, *, signal_number: Any, process_matcher: Any) -> None:
        # launch takes a signal.Signals, or the string 'SIGKILL'; any signal's name is
        # taken here too (launch would fail to send 'SIGUSR1' given as text)
        name = signal_number.name if isinstance(signal_number, signal.Signals) else \
            signal_number if isinstance(signal_number, str) else None
        if name is None or not hasattr(signal.Signals, name) or not name.startswith("SIG"):
            raise DslError(f"SignalProcess: signal_number must be a signal (signal.SIGUSR1, "
                           f"or 'SIGKILL'), got {signal_number!r}", caller_origin())
        self.signal_name = name
        self.process_matcher = process_matcher


class SendSignal(Entity):
    """What EmitEvent(SignalProcess(...)) does: the signal to the matched process."""

    def __init__(self, target: Any, signal_name: str, condition: Condition | None = None)\
            -> None:
        self._init_entity(condition)
        self.target = target
        self.signal_name = signal_name


EMITTED_EVENTS[SignalProcess] = lambda event, condition: SendSignal(
    getattr(event.process_matcher, "target", None), event.signal_name, condition)


class OpaqueFunction(Entity):
    """A Python function run with the launch context: at resolve time, or, inside an event
    handler, a timer or OnShutdown, by the supervisor when that event happens."""

    def __init__(self, *, function: Callable[..., Any], args: Iterable[Any] | None = None,
                 kwargs: dict[str, Any] | None = None, condition: Condition | None = None)\
            -> None:
        self._init_entity(condition)
        self.function = function
        self.args = list(args or [])
        self.kwargs = dict(kwargs or {})


class OpaqueCoroutine(Entity):
    """launch.actions.OpaqueCoroutine: an async function run on the launch's loop while the
    launch runs (called with the context unless `ignore_context`). The launch stays up until
    it returns, its completion is an OnExecutionComplete event, and a shutdown cancels it."""

    def __init__(self, *, coroutine: Callable[..., Any], args: Iterable[Any] | None = None,
                 kwargs: dict[str, Any] | None = None, ignore_context: bool = False,
                 condition: Condition | None = None) -> None:
        self._init_entity(condition)
        if not inspect.iscoroutinefunction(coroutine):
            raise DslError(f"OpaqueCoroutine expected a coroutine function (async def) for "
                           f"'coroutine', got {type(coroutine).__name__}", caller_origin())
        self.coroutine = coroutine
        self.args = list(args or [])
        self.kwargs = dict(kwargs or {})
        self.ignore_context = bool(ignore_context)

    @property
    def name(self) -> str:
        return getattr(self.coroutine, "__name__", "coroutine")


class DslOpaque(Entity):
    """SimpleLauncher's opaque-function mode: `sl.arg()` gives Python values inside."""

    def __init__(self, launcher: Any, function: Callable[[], Any]) -> None:
        self._init_entity(None)
        self.launcher = launcher
        self.function = function
