"""The session's requests, one frozen dataclass each: what a client may ask of a session
server (the fields and their meaning: session/protocol.py's docstring), and of a machine's
share. The ROS inspector's requests are in ros_requests.py, re-exported here as they are
first asked for; `from_message` and REQUESTS find them all whatever was imported.

A field's default is what the server does when the field is absent; None: the server's
own default. `changes`: how a read-only client names the refusal (client/read_only.py).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .request import REGISTRY, REQUESTS, Request, UnknownRequest, from_message, to_message
from .status import ProcessStatus, StatusReply

if TYPE_CHECKING:
    from .ros_requests import (
        BlackBox,
        BlackBoxWrite,
        CallService,
        EchoStart,
        EchoStop,
        HzMeasure,
        HzRead,
        HzWatch,
        LogLevel,
        Nodes,
        ParamsDescribe,
        ParamsDump,
        ParamsGet,
        ParamsLoad,
        ParamsSet,
        PlotFields,
        PlotStart,
        PlotStop,
        RecordStart,
        RecordStop,
        RecordTake,
        ServiceFields,
        Services,
        Topics,
        WatchQos,
        WatchRates,
    )

Json = dict[str, Any]

# --- following a session -----------------------------------------------------------------


@dataclass(frozen=True)
class Subscribe(Request[Json], op="subscribe"):
    """Events from here on; the reply is the snapshot (states, log offsets, recent events,
    arguments, the plugins' parts). `max_lines`/`interval` bound what a display is sent."""

    max_lines: int = 0
    interval: float = 0.0
    kinds: list[str] | None = None
    fair: bool = False
    only: str | None = None
    plain: bool = False
    stamps: bool = True


@dataclass(frozen=True)
class ReadStamps(Request[Json], op="stamps"):
    """The ROS stamps a plain display was sent its lines without, from line `since`; `on`:
    whether the batches after the reply carry them."""

    on: bool = False
    since: int | None = None


@dataclass(frozen=True)
class SetView(Request[Json], op="view"):
    """The one process whose output this client is sent (None: all)."""

    only: str | None = None


@dataclass(frozen=True)
class Status(Request[StatusReply], op="status"):
    """Each process's state, command and figures (status.py); `resources=False` spares the
    sampling."""

    resources: bool = True


@dataclass(frozen=True)
class Find(Request[str], op="find"):
    """A process id from what a user typed (id, full or unique node name)."""

    process: str

    def reply(self, result: Any) -> str:
        return str(result)


@dataclass(frozen=True)
class ReadLog(Request[Json], op="read_log"):
    """A process's log file (or launch.log, `LAUNCH_LOG`) read by the server."""

    process: str
    start: int = 0
    end: int | None = None
    skip: int = 0
    limit: int | None = None
    tail: bool = False


@dataclass(frozen=True)
class WatchResources(Request[Json], op="watch_resources"):
    """CPU and memory events while on; `processes`: those whose figures are shown;
    `trend`: those whose last minutes are drawn."""

    on: bool = True
    processes: list[str] | None = None
    trend: list[str] | None = None


# --- changing the launch -----------------------------------------------------------------


@dataclass(frozen=True)
class Start(Request[Json], op="start", changes="starting a process"):
    process: str


@dataclass(frozen=True)
class Stop(Request[Json], op="stop", changes="stopping a process"):
    process: str


@dataclass(frozen=True)
class Restart(Request[Json], op="restart", changes="restarting a process"):
    """A restart; `prefix` (a tool), `log_level` and `terminal` stay until a restart
    without them ("" log level drops it)."""

    process: str
    prefix: str | None = None
    log_level: str | None = None
    terminal: bool = False


@dataclass(frozen=True)
class RunAction(Request[Json], op="run_action", changes="running an action again"):
    action: str


@dataclass(frozen=True)
class ShutdownLaunch(Request[Json], op="shutdown", changes="stopping the launch"):
    reason: str | None = None


@dataclass(frozen=True)
class Kill(Request[Json], op="kill", changes="killing the launch"):
    """SIGKILL what is left of a shutdown."""


@dataclass(frozen=True)
class Apply(Request[Json], op="apply", changes="relaunching with other arguments"):
    arguments: dict[str, str]


@dataclass(frozen=True)
class GetPlan(Request[Json], op="plan"):
    """The plan the session runs, as JSON, with its arguments."""


@dataclass(frozen=True)
class PlanShown(Request[Json], op="plan_shown", changes="starting the launch"):
    """The session's owner (the TUI of `tuilaunch FILE`) shows the plan the server sent: the
    server starts the launch's processes now (session/owner_gate.py)."""


@dataclass(frozen=True)
class PreviewArguments(Request[Json], op="preview"):
    """What `apply` with these values would do."""

    arguments: dict[str, str]
    running: list[str] | None = None


@dataclass(frozen=True)
class TakeKeys(Request[Json], op="typing", changes="typing into a node"):
    """Takes (`on`) or gives back the keyboard of a process."""

    process: str
    on: bool = False


@dataclass(frozen=True)
class Input(Request[Json], op="input", changes="typing into a node"):
    """Keys typed into the process whose keyboard this client holds."""

    process: str
    data: str


@dataclass(frozen=True)
class LifecycleState(Request[Json], op="lifecycle"):
    """A managed node's state, asked of the node."""

    process: str


@dataclass(frozen=True)
class Transition(Request[bool], op="transition", changes="a lifecycle transition"):
    """A lifecycle transition asked of a node; the reply: whether it was made."""

    process: str
    transition: str

    def reply(self, result: Any) -> bool:
        return bool((result or {}).get("done"))


# --- a machine's share of a placed launch ------------------------------------------------


@dataclass(frozen=True)
class ExternalEvent(Request[Json], op="external_event"):
    """A process another machine runs started or exited (`on`: start|exit)."""

    process: str
    on: str
    pid: int | None = None
    code: int | None = None


@dataclass(frozen=True)
class ShareLines(Request[Json], op="share_lines"):
    """A process's lines from byte `start` to `end` of its log file, less the first
    `skip`: what the launching side's link missed."""

    process: str
    start: int = 0
    end: int = 0
    skip: int = 0


def _ros_requests() -> Any:
    from . import ros_requests

    return ros_requests


REGISTRY.later(_ros_requests)


def __getattr__(name: str) -> Any:
    """The ROS inspector's requests, re-exported as they are first asked for: a launch that
    serves no inspector (a plain `--headless` run) does not build their 26 classes at start
    (request.py's REQUESTS loads them the same way on first read)."""
    if name.startswith("__"):  # the import system asks for __path__ and such
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    try:
        return getattr(_ros_requests(), name)
    except AttributeError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None


__all__ = [
    "REQUESTS", "Apply", "BlackBox", "BlackBoxWrite", "CallService", "EchoStart", "EchoStop",
    "ExternalEvent", "Find", "GetPlan", "HzMeasure", "HzRead", "HzWatch", "Input", "Json",
    "Kill", "LifecycleState", "LogLevel", "Nodes", "ParamsDescribe", "ParamsDump",
    "ParamsGet", "ParamsLoad", "ParamsSet", "PlanShown", "PlotFields", "PlotStart",
    "PlotStop", "PreviewArguments", "ProcessStatus", "ReadLog", "ReadStamps", "RecordStart",
    "RecordStop", "RecordTake", "Request", "Restart", "RunAction", "ServiceFields",
    "Services", "SetView", "ShareLines", "ShutdownLaunch", "Start", "Status", "StatusReply",
    "Stop", "Subscribe", "TakeKeys", "Topics", "Transition", "UnknownRequest", "WatchQos",
    "WatchRates", "WatchResources", "from_message", "to_message",
]
