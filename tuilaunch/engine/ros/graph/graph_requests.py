"""The Services and Params tabs' session requests: the graph's nodes and services, a
service's request form, a call, a node's parameters described and set.

Served by the session (through the Inspector's bridge and its names), so that a TUI
attached to a session never loads rclpy (nor the message packages: over ssh they need
not be installed where the TUI runs), as for the Topics tab. The requests (classes in
run/vocabulary/ros_requests.py, listed in run/session/protocol.py):
  nodes -> {nodes: [full name]}; services -> {services: [[name, [type]]]};
  service_fields {type} -> {fields: [FieldInfo as a dict, children nested]};
  call_service {service, type, request: dict, timeout?} -> {request, response} (dicts);
  params_describe {node} -> {parameters: [ParameterInfo as a dict]};
  params_set {node, values: {name: value}} -> {results: [{name, ok, reason}]};
  params_get {node, names: [name]} -> {values: {name: value}}.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Awaitable, Callable
from typing import Any

from ...errors import LaunchError
from ...run.plugins import Handlers
from ...run.vocabulary.ros_requests import (
    CallService,
    Nodes,
    ParamsDescribe,
    ParamsGet,
    ParamsSet,
    ServiceFields,
    Services,
)
from ..ros_errors import RosError

CALL_TIMEOUT = 5.0
"""A service call's answer is waited for this long unless the client says otherwise."""
MOST_CALL_TIMEOUT = 60.0


class GraphRequests:
    """The requests, answered through the Inspector's `bridge()` (the launch's, made on the
    first need) and `current_name(ref)` (a node named by its process id, or in full)."""

    def __init__(self, bridge: Callable[[], Awaitable[Any]],
                 current_name: Callable[[Any], Awaitable[str]], service_timeout: float) -> None:
        self.bridge = bridge
        self.current_name = current_name
        self.service_timeout = service_timeout

    def handlers(self) -> Handlers:
        return {Nodes: self.nodes, Services: self.services,
                ServiceFields: self.service_fields, CallService: self.call_service,
                ParamsDescribe: self.params_describe, ParamsSet: self.params_set,
                ParamsGet: self.params_get}

    async def nodes(self, request: Nodes, client: int) -> dict[str, Any]:
        bridge = await self.bridge()
        return {"nodes": await bridge.list_nodes()}

    async def services(self, request: Services, client: int) -> dict[str, Any]:
        bridge = await self.bridge()
        return {"services": [[name, list(types)]
                             for name, types in await bridge.list_services()]}

    async def service_fields(self, request: ServiceFields, client: int) -> dict[str, Any]:
        # imported on the first form: a launch that never shows one never loads them
        from ..messages import describe_fields, import_type

        # MessageError (a type not installed where the session runs) is the refusal
        fields = describe_fields(import_type(_text(request.type, "service_fields", "type"))
                                 .Request)
        return {"fields": [dataclasses.asdict(f) for f in fields]}

    async def call_service(self, request: CallService, client: int) -> dict[str, Any]:
        service = _text(request.service, request.op, "service")
        type_name = _text(request.type, request.op, "type")
        timeout = request.timeout or CALL_TIMEOUT
        bridge = await self.bridge()
        try:
            sent, response = await bridge.call_service(
                service, request.request, timeout=min(timeout, MOST_CALL_TIMEOUT),
                service_type=type_name)
        except RosError as exc:
            raise LaunchError(f"{service}: {exc}") from None
        return {"request": sent, "response": response}

    async def params_describe(self, request: ParamsDescribe, client: int) -> dict[str, Any]:
        node = await self.current_name(request.node)
        described = await self._ask(node, lambda bridge: bridge.describe_parameters(
            node, timeout=self.service_timeout))
        return {"parameters": [dataclasses.asdict(p) for p in described]}

    async def params_set(self, request: ParamsSet, client: int) -> dict[str, Any]:
        node = await self.current_name(request.node)
        values = request.values
        if not values:
            raise ValueError("params_set needs values: {name: value}")
        results = await self._ask(node, lambda bridge: bridge.set_parameters(
            node, values, timeout=self.service_timeout))
        return {"results": [{"name": r.name, "ok": r.successful, "reason": r.reason}
                            for r in results]}

    async def params_get(self, request: ParamsGet, client: int) -> dict[str, Any]:
        node = await self.current_name(request.node)
        names = request.names
        if not all(isinstance(n, str) for n in names):
            raise ValueError("params_get needs names: [name]")
        return {"values": await self._ask(node, lambda bridge: bridge.get_parameters(
            node, names, timeout=self.service_timeout))}

    async def _ask(self, node: str, call: Callable[[Any], Awaitable[Any]]) -> Any:
        """`call(bridge)`, a request to `node`; a node that does not answer is said so."""
        bridge = await self.bridge()
        try:
            return await call(bridge)
        except RosError as exc:
            raise LaunchError(f"{node} does not answer: {exc}") from None


def _text(value: str, op: str, key: str) -> str:
    if not value:
        raise ValueError(f"{op} needs {key}")
    return value
