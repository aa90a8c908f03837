"""The ROS inspector's session requests, one frozen dataclass each: topics, rates, echo,
plots, parameters, loggers, the Services and Params tabs' calls, recordings and the black
box (answered by engine/ros/; the fields and replies: session/protocol.py's docstring).

A field's default is what the server does when it is absent; None: the server's own.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .request import Request

Json = dict[str, Any]


@dataclass(frozen=True)
class Topics(Request[Json], op="topics"):
    """The graph's topics (of one node), their endpoints and QoS problems."""

    node: str | None = None
    problems_only: bool = False


@dataclass(frozen=True)
class HzMeasure(Request[Json], op="hz"):
    """A topic's rate, measured over `window` s, then answered."""

    topic: str
    window: float | None = None


@dataclass(frozen=True)
class HzWatch(Request[Json], op="hz_watch"):
    """`tuilaunch hz`: "hz" events over the last `messages` messages every `every` s."""

    topic: str
    messages: int = 10000
    every: float | None = None


@dataclass(frozen=True)
class HzRead(Request[Json], op="hz_read"):
    topic: str


@dataclass(frozen=True)
class WatchRates(Request[Json], op="watch_rates"):
    """The topics whose rates this client is sent ([]: none)."""

    topics: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class EchoStart(Request[Json], op="echo"):
    """"echo" events of a topic's messages; `max_per_s` 0: every one."""

    topic: str
    count: int | None = None
    max_per_s: float | None = None
    wait: float | None = None


@dataclass(frozen=True)
class EchoStop(Request[Json], op="echo_stop"):
    topic: str


@dataclass(frozen=True)
class WatchQos(Request[Json], op="watch_qos"):
    on: bool = True


@dataclass(frozen=True)
class PlotFields(Request[Json], op="plot_fields"):
    """A topic's type and its numeric fields."""

    topic: str


@dataclass(frozen=True)
class PlotStart(Request[Json], op="plot"):
    """"plot" events of these fields of a topic (`raw`: every message)."""

    topic: str
    fields: list[str]
    raw: bool = False
    tag: Any = None
    stamp: bool = False
    wait: float | None = None


@dataclass(frozen=True)
class PlotStop(Request[Json], op="plot_stop"):
    topic: str


@dataclass(frozen=True)
class ParamsDump(Request[Json], op="params_dump"):
    node: str


@dataclass(frozen=True)
class ParamsLoad(Request[Json], op="params_load", changes="loading parameters"):
    node: str
    yaml: str
    source: str | None = None


@dataclass(frozen=True)
class LogLevel(Request[Json], op="log_level", changes="setting a logger level"):
    node: str
    level: str


@dataclass(frozen=True)
class Nodes(Request[Json], op="nodes"):
    """The graph's nodes."""


@dataclass(frozen=True)
class Services(Request[Json], op="services"):
    """The graph's services and their types."""


@dataclass(frozen=True)
class ServiceFields(Request[Json], op="service_fields"):
    """A service type's request form."""

    type: str


@dataclass(frozen=True)
class CallService(Request[Json], op="call_service", changes="calling a service"):
    service: str
    type: str
    request: Json = field(default_factory=dict)
    timeout: float | None = None


@dataclass(frozen=True)
class ParamsDescribe(Request[Json], op="params_describe"):
    node: str


@dataclass(frozen=True)
class ParamsSet(Request[Json], op="params_set", changes="setting a parameter"):
    node: str
    values: Json


@dataclass(frozen=True)
class ParamsGet(Request[Json], op="params_get"):
    node: str
    names: list[str]


@dataclass(frozen=True)
class RecordStart(Request[Json], op="record_start"):
    """A recording of these topics (none: all) on the session's side."""

    topics: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class RecordTake(Request[Json], op="record_take"):
    """A recording's messages since the last take, waiting `wait` s for some."""

    recording: int
    wait: float | None = None


@dataclass(frozen=True)
class RecordStop(Request[Json], op="record_stop"):
    recording: int


@dataclass(frozen=True)
class BlackBox(Request[Json], op="black_box"):
    """The black box: `seconds` switches it on (0: off), without: how it is."""

    seconds: float | None = None
    size: int | None = None


@dataclass(frozen=True)
class BlackBoxWrite(Request[Json], op="black_box_write"):
    """The black box written to a file now."""


__all__ = [
    "BlackBox", "BlackBoxWrite", "CallService", "EchoStart", "EchoStop", "HzMeasure",
    "HzRead", "HzWatch", "LogLevel", "Nodes", "ParamsDescribe", "ParamsDump", "ParamsGet",
    "ParamsLoad", "ParamsSet", "PlotFields", "PlotStart", "PlotStop", "RecordStart",
    "RecordStop", "RecordTake", "ServiceFields", "Services", "Topics", "WatchQos",
    "WatchRates",
]
