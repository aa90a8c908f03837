"""What the bridge and its helpers share: its error, its results, and the calls the helpers
(loggers, param_files, rates, echo) make on a bridge, as a Protocol.

The helpers import this, never bridge.py, and the bridge imports them: one direction, no
cycle (bridge -> loggers -> calls <- bridge).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

from .ros_errors import RosError as RosError  # where the helpers and the bridge take it from


@dataclass
class ParameterInfo:
    name: str
    type: str
    value: Any
    description: str
    read_only: bool
    constraints: str


@dataclass
class SetResult:
    name: str
    successful: bool
    reason: str


class BridgeCalls(Protocol):
    """The calls of a RosBridge (bridge.py) its helpers make."""

    async def list_nodes(self) -> list[str]: ...

    async def list_services(self) -> list[tuple[str, list[str]]]: ...

    async def call_typed(self, name: str, service_class: Any, request: Any,
                         timeout: float) -> Any: ...

    async def list_parameters(self, node: str, timeout: float = 5.0) -> list[str]: ...

    async def get_parameters(self, node: str, names: list[str],
                             timeout: float = 5.0) -> dict[str, Any]: ...

    async def describe_parameters(self, node: str, names: list[str] | None = None,
                                  timeout: float = 5.0) -> list[ParameterInfo]: ...

    async def set_parameters(self, node: str, values: dict[str, Any],
                             timeout: float = 5.0) -> list[SetResult]: ...
