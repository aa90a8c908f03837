"""The launch's own ROS actions: `call_service` and `set_parameters` through the bridge.

A supervisor plugin (run/plugins.py). It also owns the launch's bridge (rclpy in its own
thread), which the lifecycle and composition plugins share: made on first use, or supplied
by the caller (the TUI shares its own), and only closed here when it was made here.
"""

from __future__ import annotations

import asyncio
import os
import sys
import threading
from collections.abc import Callable, Mapping
from typing import Any

from ..plan.model import ActionKind, ActionPlan
from ..run.events import Event, Log
from ..run.plugins import ActionRunner, Plugin
from .ros_errors import MessageError, RosError

Emit = Callable[[Event], None]

CLOSE_WITHIN = 10.0
"""Seconds a stop waits for rclpy to shut down. Fast DDS can hang in it (a writer's timer
waiting for the event thread, seen once under load in a full test run): the session ends
all the same, its processes stopped, rather than never."""

CLOSE_HUNG = threading.Event()
"""Set when rclpy did not shut down in time: the process then ends without running the
DDS library's own exit code, which would wait on the same lock (`exit_now_if_hung`)."""


def exit_now_if_hung(status: int) -> None:
    """Ends the process at once, with `status`, when rclpy's shutdown hung."""
    if CLOSE_HUNG.is_set():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(status)


class RosActions(Plugin):
    # a call waiting for a service that never comes must not hold a shutdown
    detached_actions = frozenset({ActionKind.CALL_SERVICE, ActionKind.SET_PARAMETERS})

    def __init__(self, bridge_factory: Callable[[], Any] | None, service_timeout: float,
                 emit: Emit) -> None:
        self._bridge: Any = None
        self._bridge_factory = bridge_factory  # whoever supplies the bridge also closes it
        self.service_timeout = service_timeout
        self._emit_to = emit

    def actions(self) -> Mapping[str, ActionRunner]:
        return {ActionKind.CALL_SERVICE: self.call_service,
                ActionKind.SET_PARAMETERS: self.set_parameters}

    def log(self, action: ActionPlan, text: str, level: str = "INFO") -> None:
        self._emit_to(Log(action.id, reason=text, level=level))

    @property
    def made(self) -> Any:
        """The bridge if one exists already, else None (never makes one)."""
        return self._bridge

    async def close(self) -> None:
        if self._bridge is not None and self._bridge_factory is None:
            # a daemon thread of its own: a pool's thread stuck in the DDS library would be
            # waited for at exit
            closing = threading.Thread(target=self._bridge.close, name="ros-bridge-close",
                                       daemon=True)
            closing.start()
            await asyncio.to_thread(closing.join, CLOSE_WITHIN)
            if closing.is_alive():
                CLOSE_HUNG.set()
                self._emit_to(Log("launch", level="WARN", reason=(
                    f"rclpy did not shut down within {CLOSE_WITHIN:g} s (a hang in the DDS "
                    "library): the launch ends without it")))

    def bridge(self) -> Any:
        """Made on first use: a launch without ROS actions never starts rclpy here."""
        if self._bridge is None:
            if self._bridge_factory is not None:
                self._bridge = self._bridge_factory()
            else:
                from .bridge import RosBridge

                self._bridge = RosBridge()
        return self._bridge

    async def call_service(self, action: ActionPlan) -> bool:
        name = str(action.target)
        self.log(action, f"waiting for service {name}")
        try:
            bridge = self.bridge()
            service_type = await bridge.wait_for_service(name, None)
            request, response = await bridge.call_service(
                name, action.data, self.service_timeout, service_type=service_type)
        except (RosError, MessageError) as exc:
            self.log(action, f"call_service {name} failed: {exc}", "ERROR")
            return False
        if "req" in action.verbosity:
            self.log(action, f"{name} ({service_type}) request: {request}")
        if "res" in action.verbosity:
            self.log(action, f"{name} response: {response}")
        return True

    async def set_parameters(self, action: ActionPlan) -> bool:
        node = str(action.target)
        self.log(action, f"waiting for node {node}")
        try:
            bridge = self.bridge()
            await bridge.wait_for_service(f"{node}/set_parameters", None)
            results = await bridge.set_parameters(node, action.data, self.service_timeout)
        except (RosError, MessageError) as exc:
            self.log(action, f"set_parameters on {node} failed: {exc}", "ERROR")
            return False
        if "req" in action.verbosity:
            self.log(action, f"{node} parameters requested: {action.data}")
        for result in results:
            if not result.successful:
                self.log(action, f"{node} refused {result.name}="
                          f"{action.data.get(result.name)!r}: {result.reason}", "ERROR")
            elif "res" in action.verbosity:
                self.log(action, f"{node} set {result.name}={action.data.get(result.name)!r}")
        return all(r.successful for r in results)
