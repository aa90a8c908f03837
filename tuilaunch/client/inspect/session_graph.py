"""The ROS graph as the Services and Params tabs ask it: `GraphCalls`, answered by the
session server where the nodes run (`SessionGraph`), so that a client never loads rclpy
nor the message packages (over ssh they need not be installed where the TUI runs).

`GraphCalls` is what those tabs need: the session's requests (engine/ros/graph_requests.py)
one for one. The launch's bridge (engine/ros/bridge.py, `RosBridge`) has the same calls.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any, Protocol

from ...engine.ros.calls import ParameterInfo, SetResult
from ...engine.ros.messages import FieldInfo
from ...engine.run.vocabulary import ros_requests as rq


class GraphCalls(Protocol):
    """The graph's nodes and services, a service's request form and call, a node's
    parameters. Failures raise an error whose text says why (shown in the panel)."""

    async def list_nodes(self) -> list[str]: ...

    async def list_services(self) -> list[tuple[str, list[str]]]: ...

    async def service_fields(self, type_name: str) -> list[FieldInfo]: ...

    async def call_service(self, name: str, request: dict[str, Any], timeout: float = 5.0,
                           wait: float | None = 0.0, service_type: str | None = None)\
        -> tuple[dict[str, Any], dict[str, Any]]: ...

    async def describe_parameters(self, node: str, names: list[str] | None = None,
                                  timeout: float = 5.0) -> list[ParameterInfo]: ...

    async def set_parameters(self, node: str, values: dict[str, Any], timeout: float = 5.0)\
        -> list[SetResult]: ...

    async def get_parameters(self, node: str, names: list[str], timeout: float = 5.0)\
        -> dict[str, Any]: ...


class SessionGraph:
    """GraphCalls through a session's requests: `request(request)` is the client's
    (RemoteSupervisor.request, run where the client's link lives)."""

    def __init__(self, request: Callable[..., Awaitable[Any]]) -> None:
        self.request = request

    async def list_nodes(self) -> list[str]:
        return [str(name) for name in (await self.request(rq.Nodes()))["nodes"]]

    async def list_services(self) -> list[tuple[str, list[str]]]:
        return [(str(name), [str(t) for t in types])
                for name, types in (await self.request(rq.Services()))["services"]]

    async def service_fields(self, type_name: str) -> list[FieldInfo]:
        return [field_info(f) for f in
                (await self.request(rq.ServiceFields(type=type_name)))["fields"]]

    async def call_service(self, name: str, request: dict[str, Any], timeout: float = 5.0,
                           wait: float | None = 0.0, service_type: str | None = None)\
            -> tuple[dict[str, Any], dict[str, Any]]:
        result = await self.request(rq.CallService(service=name, type=service_type or "",
                                                request=request, timeout=timeout))
        return result["request"], result["response"]

    async def describe_parameters(self, node: str, names: list[str] | None = None,
                                  timeout: float = 5.0) -> list[ParameterInfo]:
        result = await self.request(rq.ParamsDescribe(node=node))
        return [ParameterInfo(**p) for p in result["parameters"]
                if names is None or p["name"] in names]

    async def set_parameters(self, node: str, values: dict[str, Any], timeout: float = 5.0)\
            -> list[SetResult]:
        result = await self.request(rq.ParamsSet(node=node, values=values))
        return [SetResult(r["name"], bool(r["ok"]), str(r["reason"] or ""))
                for r in result["results"]]

    async def get_parameters(self, node: str, names: list[str], timeout: float = 5.0)\
            -> dict[str, Any]:
        answer = await self.request(rq.ParamsGet(node=node, names=names))
        values: dict[str, Any] = answer["values"]
        return values


def field_info(data: dict[str, Any]) -> FieldInfo:
    """A FieldInfo back from its dict (dataclasses.asdict), its children too."""
    return FieldInfo(data["name"], data["type"], data["default"], bool(data["is_sequence"]),
                     [field_info(child) for child in data.get("children") or []])
