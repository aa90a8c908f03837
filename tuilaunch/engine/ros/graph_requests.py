"""The Services and Params tabs' session requests: the graph's nodes and services, a
service's request form, a call, a node's parameters described and set.

Served by the session (through the Inspector's bridge and its names), so that a TUI
attached to a session never loads rclpy (nor the message packages: over ssh they need
not be installed where the TUI runs), as for the Topics tab. The ops (listed in
run/session/protocol.py):
  nodes -> {nodes: [full name]}; services -> {services: [[name, [type]]]};
  service_fields {type} -> {fields: [FieldInfo as a dict, children nested]};
  call_service {service, type, request: dict, timeout?} -> {request, response} (dicts);
  params_describe {node} -> {parameters: [ParameterInfo as a dict]};
  params_set {node, values: {name: value}} -> {results: [{name, ok, reason}]};
  params_get {node, names: [name]} -> {values: {name: value}}.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Awaitable, Callable, Mapping
from typing import Any

from ..errors import LaunchError
from ..run.plugins import Handler
from .ros_errors import RosError

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

    def handlers(self) -> Mapping[str, Handler]:
        return {"nodes": self.nodes, "services": self.services,
                "service_fields": self.service_fields, "call_service": self.call_service,
                "params_describe": self.params_describe, "params_set": self.params_set,
                "params_get": self.params_get}

    async def nodes(self, message: dict[str, Any]) -> dict[str, Any]:
        bridge = await self.bridge()
        return {"nodes": await bridge.list_nodes()}

    async def services(self, message: dict[str, Any]) -> dict[str, Any]:
        bridge = await self.bridge()
        return {"services": [[name, list(types)]
                             for name, types in await bridge.list_services()]}

    async def service_fields(self, message: dict[str, Any]) -> dict[str, Any]:
        # imported on the first form: a launch that never shows one never loads them
        from .messages import describe_fields, import_type

        # MessageError (a type not installed where the session runs) is the refusal
        fields = describe_fields(import_type(_text(message, "type")).Request)
        return {"fields": [dataclasses.asdict(f) for f in fields]}

    async def call_service(self, message: dict[str, Any]) -> dict[str, Any]:
        service, type_name = _text(message, "service"), _text(message, "type")
        request = message.get("request") or {}
        if not isinstance(request, dict):
            raise ValueError("call_service needs the request as an object")
        timeout = float(message.get("timeout") or CALL_TIMEOUT)
        bridge = await self.bridge()
        try:
            sent, response = await bridge.call_service(
                service, request, timeout=min(timeout, MOST_CALL_TIMEOUT),
                service_type=type_name)
        except RosError as exc:
            raise LaunchError(f"{service}: {exc}") from None
        return {"request": sent, "response": response}

    async def params_describe(self, message: dict[str, Any]) -> dict[str, Any]:
        node = await self.current_name(message.get("node"))
        bridge = await self.bridge()
        try:
            described = await bridge.describe_parameters(node, timeout=self.service_timeout)
        except RosError as exc:
            raise LaunchError(f"{node} does not answer: {exc}") from None
        return {"parameters": [dataclasses.asdict(p) for p in described]}

    async def params_set(self, message: dict[str, Any]) -> dict[str, Any]:
        node = await self.current_name(message.get("node"))
        values = message.get("values")
        if not isinstance(values, dict) or not values:
            raise ValueError("params_set needs values: {name: value}")
        bridge = await self.bridge()
        try:
            results = await bridge.set_parameters(node, values, timeout=self.service_timeout)
        except RosError as exc:
            raise LaunchError(f"{node} does not answer: {exc}") from None
        return {"results": [{"name": r.name, "ok": r.successful, "reason": r.reason}
                            for r in results]}

    async def params_get(self, message: dict[str, Any]) -> dict[str, Any]:
        node = await self.current_name(message.get("node"))
        names = message.get("names")
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise ValueError("params_get needs names: [name]")
        bridge = await self.bridge()
        try:
            values = await bridge.get_parameters(node, names, timeout=self.service_timeout)
        except RosError as exc:
            raise LaunchError(f"{node} does not answer: {exc}") from None
        return {"values": values}


def _text(message: dict[str, Any], key: str) -> str:
    value = message.get(key)
    if not isinstance(value, str) or not value:
        raise ValueError(f"{message.get('op')} needs {key}")
    return value
