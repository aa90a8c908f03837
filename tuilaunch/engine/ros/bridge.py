"""RosBridge: the launcher's one rclpy context, spinning in its own thread.

Everything here is awaited from asyncio and has a timeout, so an unresponsive node never
blocks the supervisor's or the UI's loop. Domain and discovery settings come from the
environment (ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE), as for any node.
"""

from __future__ import annotations

import asyncio
import os
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from .calls import ParameterInfo, RosError, SetResult
from .messages import FieldInfo, MessageError, describe_fields, fill, import_type, to_plain

if TYPE_CHECKING:
    from ..plan.model import Plan

PARAMETER_TYPES = {0: "not set", 1: "bool", 2: "int", 3: "float", 4: "str", 5: "bytes",
                   6: "bool[]", 7: "int[]", 8: "float[]", 9: "str[]"}


def parameter_value(value: Any) -> Any:
    """A Python value as rcl_interfaces/ParameterValue, typed from the value itself."""
    from rcl_interfaces.msg import ParameterValue

    msg = ParameterValue()
    if isinstance(value, bool):
        msg.type, msg.bool_value = 1, value
    elif isinstance(value, int):
        msg.type, msg.integer_value = 2, value
    elif isinstance(value, float):
        msg.type, msg.double_value = 3, value
    elif isinstance(value, str):
        msg.type, msg.string_value = 4, value
    elif isinstance(value, bytes):
        msg.type, msg.byte_array_value = 5, list(value)
    elif isinstance(value, list) and value and all(isinstance(v, bool) for v in value):
        msg.type, msg.bool_array_value = 6, value
    elif isinstance(value, list) and value and all(
            isinstance(v, int) and not isinstance(v, bool) for v in value):
        msg.type, msg.integer_array_value = 7, value
    elif isinstance(value, list) and value and all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value):
        msg.type, msg.double_array_value = 8, [float(v) for v in value]
    elif isinstance(value, list) and all(isinstance(v, str) for v in value):
        msg.type, msg.string_array_value = 9, value
    else:
        raise MessageError(f"value {value!r} has no ROS parameter type")
    return msg


def python_value(msg: Any) -> Any:
    field = {1: "bool_value", 2: "integer_value", 3: "double_value", 4: "string_value",
             5: "byte_array_value", 6: "bool_array_value", 7: "integer_array_value",
             8: "double_array_value", 9: "string_array_value"}.get(msg.type)
    return None if field is None else to_plain(getattr(msg, field))


DISCOVERY_S = 1.0
"""A graph listing waits until the bridge's participant is this old: a new participant
knows no other node yet (ros2cli's direct node spins 0.5 s before it lists, for the same
reason), and the TUI's Params and Services tabs, whose first look starts the bridge, list
once. Twice ros2cli's wait: the machines this runs on are often busy."""

MAX_DOMAIN_ID = 232
"""The highest domain whose DDS ports fit below 65536 (7400 + 250 x domain + offsets)."""


def check_domain_id() -> None:
    """rmw_fastrtps ends the whole process (exit status 1, no exception) when a node is made
    in a domain whose ports do not fit: a bad ROS_DOMAIN_ID must be an error the caller
    reports, never the end of the launcher and its launch."""
    text = os.environ.get("ROS_DOMAIN_ID", "").strip()
    if not text:
        return
    try:
        value = int(text)
    except ValueError:
        raise RosError(f"ROS_DOMAIN_ID={text!r} is not a number") from None
    if not 0 <= value <= MAX_DOMAIN_ID:
        raise RosError(f"ROS_DOMAIN_ID={value} is out of range (0-{MAX_DOMAIN_ID})")


class RosBridge:
    def __init__(self, node_name: str | None = None) -> None:
        check_domain_id()
        # one name per process (a session's server, each TUI): several nodes of one name
        # make `ros2 node list` warn and confuse who is who
        node_name = node_name or f"tuilaunch_{os.getpid()}"
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import MultiThreadedExecutor

        self._born = time.monotonic()
        self._context = Context()
        # args=[]: otherwise rclpy reads tuilaunch's own argv, where `name:=value` launch
        # arguments look like (deprecated) remapping rules
        rclpy.init(args=[], context=self._context, signal_handler_options=_no_signal_handlers())
        self.node = rclpy.create_node(node_name, context=self._context,
                                      start_parameter_services=False)
        self._clients: dict[tuple[str, Any], Any] = {}
        self._clients_lock = threading.Lock()
        self._executor = MultiThreadedExecutor(num_threads=2, context=self._context)
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name="ros-bridge", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        try:
            self._executor.spin()
        except Exception:  # the context was shut down under the executor: nothing to do
            pass

    def close(self) -> None:
        meter = getattr(self, "inspector_rates", None)
        if meter is not None:  # its thread lets go of its subscriptions while the node is
            meter.close()
        self._executor.shutdown(timeout_sec=2)
        self.node.destroy_node()
        self._context.try_shutdown()
        self._thread.join(timeout=5)

    # --- graph ---------------------------------------------------------------------------

    async def _discovered(self) -> None:
        """Returns once discovery has had its time (at once after the first second)."""
        left = self._born + DISCOVERY_S - time.monotonic()
        if left > 0:
            await asyncio.sleep(left)

    async def list_nodes(self) -> list[str]:
        await self._discovered()
        pairs = await asyncio.to_thread(self.node.get_node_names_and_namespaces)
        return sorted((ns.rstrip("/") + "/" + name) for name, ns in pairs
                      if name != self.node.get_name())

    async def list_services(self) -> list[tuple[str, list[str]]]:
        await self._discovered()
        found = await asyncio.to_thread(self.node.get_service_names_and_types)
        return sorted((name, list(types)) for name, types in found)

    async def count_publishers(self, topic: str) -> int:
        return int(await asyncio.to_thread(self.node.count_publishers, topic))

    async def wait_for_service(self, name: str, timeout: float | None) -> str:
        """The service's type once it appears on the graph."""
        loop = asyncio.get_running_loop()
        deadline = None if timeout is None else loop.time() + timeout
        while True:
            for service, types in await self.list_services():
                if service == name and types:
                    return types[0]
            if deadline is not None and loop.time() > deadline:
                raise RosError(f"service {name} did not appear within {timeout:g} s")
            await asyncio.sleep(0.1)

    # --- calls ---------------------------------------------------------------------------

    async def call_typed(self, name: str, service_class: Any, request: Any,
                         timeout: float) -> Any:
        client = self._client(name, service_class)
        loop = asyncio.get_running_loop()
        deadline = loop.time() + timeout
        while not client.service_is_ready():
            if loop.time() > deadline:
                raise RosError(f"service {name} is not available")
            await asyncio.sleep(0.05)
        done: asyncio.Future[Any] = loop.create_future()
        pending = client.call_async(request)

        def finished(future: Any) -> None:
            loop.call_soon_threadsafe(_settle, done, future)

        pending.add_done_callback(finished)
        try:
            return await asyncio.wait_for(done, max(deadline - loop.time(), 0.1))
        except TimeoutError:
            client.remove_pending_request(pending)
            raise RosError(f"service {name} did not answer within {timeout:g} s") from None

    def _client(self, name: str, service_class: Any) -> Any:
        """One client per service and type, kept: a server drops its reply to a client it
        has not matched yet (Fast DDS: "client will not receive response"), so a client made
        per call loses answers on a busy machine, where matching takes longer."""
        key = (name, service_class)
        with self._clients_lock:
            client = self._clients.get(key)
            if client is None:
                client = self._clients[key] = self.node.create_client(service_class, name)
            return client

    def drop_clients(self, keep: Callable[[str], bool]) -> list[str]:
        """Destroys the kept clients of the services `keep` refuses; their names. A client
        is an endpoint of its service: kept after a relaunch moved its node (robot:=r1 ->
        r2), it would keep /r1/talker/get_parameters listed on the graph for good."""
        with self._clients_lock:
            stale = [key for key in self._clients if not keep(key[0])]
            for key in stale:
                self.node.destroy_client(self._clients.pop(key))
        return sorted({name for name, _ in stale})

    async def call_service(self, name: str, request: dict[str, Any], timeout: float = 5.0,
                           wait: float | None = 0.0, service_type: str | None = None)\
            -> tuple[dict[str, Any], dict[str, Any]]:
        """Calls a service with a request built from a dict; (request, response) as dicts."""
        if service_type is None:
            service_type = await self.wait_for_service(name, wait)
        service_class = import_type(service_type)
        message = fill(service_class.Request(), request)
        response = await self.call_typed(name, service_class, message, timeout)
        return to_plain(message), to_plain(response)

    async def service_fields(self, type_name: str) -> list[FieldInfo]:
        """A service's request fields, for a form (MessageError: the type is not here)."""
        return describe_fields(import_type(type_name).Request)

    # --- parameters ----------------------------------------------------------------------

    async def list_parameters(self, node: str, timeout: float = 5.0) -> list[str]:
        from rcl_interfaces.srv import ListParameters

        response = await self.call_typed(f"{node}/list_parameters", ListParameters,
                                         ListParameters.Request(), timeout)
        return sorted(response.result.names)

    async def get_parameters(self, node: str, names: list[str], timeout: float = 5.0)\
            -> dict[str, Any]:
        from rcl_interfaces.srv import GetParameters

        response = await self.call_typed(f"{node}/get_parameters", GetParameters,
                                         GetParameters.Request(names=names), timeout)
        return {n: python_value(v) for n, v in zip(names, response.values, strict=False)}

    async def describe_parameters(self, node: str, names: list[str] | None = None,
                                  timeout: float = 5.0) -> list[ParameterInfo]:
        from rcl_interfaces.srv import DescribeParameters

        if names is None:
            names = await self.list_parameters(node, timeout)
        response = await self.call_typed(f"{node}/describe_parameters", DescribeParameters,
                                         DescribeParameters.Request(names=names), timeout)
        values = await self.get_parameters(node, names, timeout)
        return [ParameterInfo(d.name, PARAMETER_TYPES.get(d.type, str(d.type)),
                              values.get(d.name), d.description, d.read_only,
                              d.additional_constraints)
                for d in response.descriptors]

    async def set_parameters(self, node: str, values: dict[str, Any], timeout: float = 5.0)\
            -> list[SetResult]:
        """Each parameter's outcome, with the node's reason when it refused."""
        from rcl_interfaces.msg import Parameter
        from rcl_interfaces.srv import SetParameters

        params = [Parameter(name=name, value=parameter_value(value))
                  for name, value in values.items()]
        response = await self.call_typed(f"{node}/set_parameters", SetParameters,
                                         SetParameters.Request(parameters=params), timeout)
        return [SetResult(p.name, r.successful, r.reason)
                for p, r in zip(params, response.results, strict=False)]


    # --- inspector: topics, rates, echo, parameter files, logger levels ------------------
    # Thin: the logic lives in graph, rates, echo, param_files and loggers.

    async def topics(self, processes: dict[str, str] | None = None,
                     node: str | None = None) -> dict[str, Any]:
        """`{"topics": [...]}` (see graph.topics_graph); `node` keeps that node's topics."""
        from .graph.topic_graph import topics_graph

        return await asyncio.to_thread(topics_graph, self.node, processes, node)

    def rate_meter(self) -> Any:
        """The bridge's one RateMeter, made on first use."""
        from .graph.rates import RateMeter

        # made here rather than in __init__: most sessions never measure a rate
        meter = getattr(self, "inspector_rates", None)
        if meter is None:
            meter = self.inspector_rates = RateMeter(self.node)
        return meter

    async def start_rates(self, topics: list[str], window_s: float = 10.0,
                          wait: float = 5.0) -> None:
        """Measures these topics from now on; RosError for a topic nobody publishes,
        MessageError for a type not installed."""
        for topic in topics:
            await self.rate_meter().start(topic, window_s, wait)

    async def stop_rates(self, topics: list[str] | None = None) -> None:
        meter = self.rate_meter()
        for topic in meter.measured() if topics is None else topics:
            meter.stop(topic)

    async def read_rates(self, topic: str | None = None) -> dict[str, dict[str, Any]]:
        """`{topic: {"topic", "rate_hz", "bytes_per_s", "messages", "window_s"}}`."""
        return dict(self.rate_meter().read(topic))

    async def start_echo(self, topic: str, wait: float = 5.0, keep: int = 100) -> Any:
        """An EchoSubscription (echo.py): `take()` / `take_yaml()` its messages."""
        from .graph.echo import start_echo

        return await start_echo(self.node, topic, wait, keep)

    async def stop_echo(self, echo: Any) -> None:
        from .graph.echo import stop_echo

        stop_echo(self.node, echo)

    async def dump_params(self, node: str, timeout: float = 5.0) -> str:
        """The node's live parameters as a params YAML a launch file loads."""
        from .param_files import dump

        return await dump(self, node, timeout)

    async def load_params(self, node: str, path: str, timeout: float = 5.0)\
            -> list[SetResult]:
        from .param_files import load

        return await load(self, node, path, timeout)

    async def set_logger_level(self, node: str, level: str | int, timeout: float = 5.0)\
            -> None:
        """loggers.NoLoggerService when the node has no logger service."""
        from .loggers import set_level

        await set_level(self, node, level, timeout=timeout)

    async def get_logger_levels(self, node: str, timeout: float = 5.0) -> dict[str, str]:
        from .loggers import get_levels

        return await get_levels(self, node, timeout=timeout)

def in_plan(plan: Plan) -> Callable[[str], bool]:
    """Whether a service may belong to a node of `plan`: under one of its nodes' full
    names or namespaces (a node named in its code is known by its namespace only; the root
    namespace alone keeps nothing, or every client would stay)."""
    roots: set[str] = set()
    for proc in plan.processes:
        if not proc.enabled:
            continue
        for name in (proc.full_name, proc.namespace if proc.kind != "process" else None,
                     *(str(c.get("full_name") or "") for c in proc.components)):
            if name and name.strip("/"):
                roots.add(name.rstrip("/") + "/")
    return lambda service: any(service.startswith(root) for root in roots)


def _settle(done: asyncio.Future[Any], future: Any) -> None:
    if done.done():
        return
    exception = future.exception()
    if exception is not None:
        done.set_exception(RosError(f"service call failed: {exception}"))
    else:
        done.set_result(future.result())


def _no_signal_handlers() -> Any:
    """rclpy must not take over SIGINT: the supervisor owns shutdown."""
    from rclpy.signals import SignalHandlerOptions

    return SignalHandlerOptions.NO
