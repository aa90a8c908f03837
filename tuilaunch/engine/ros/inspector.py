"""The inspector's session requests: topics, rates, echo, parameter files, logger levels.

A supervisor plugin (run/plugins.py) whose `handlers` the session server answers (the ops
are listed in run/protocol.py). It works through the launch's bridge (actions.py owns it)
and knows the plan, so graph endpoints are mapped to the launch's processes and a node may
be named by its process id.

Streams are per client: `watch_rates` measures the union of what the clients watch and
stops a topic when nobody watches it (rate_watch.py); `hz` measures for one client
(hz_streams.py); `echo` runs one throttled stream per client and
topic (echo_streams.py); `plot` one stream of decimated points per client and topic
(plot/streams.py); `watch_qos` sends the graph's QoS problems when they change
(qos_watch.py). A client that disconnects loses its streams (`client_gone`).
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ..errors import LaunchError
from ..run.events import Event, Output, Started
from ..run.plugins import Clients, Handler, Handlers, Plugin
from ..run.vocabulary.reported_names import ReportedNames
from ..run.vocabulary.request import Request
from ..run.vocabulary.ros_requests import LogLevel, ParamsDump, ParamsLoad, Topics
from .actions import RosActions
from .graph.echo_streams import EchoStreams
from .graph.graph_requests import GraphRequests
from .graph.hz_streams import HzStreams
from .graph.qos_watch import Problems, QosWatch
from .graph.rate_watch import RateWatch
from .graph.stream_hooks import StreamHooks
from .plot.streams import PlotStreams
from .ros_errors import RosError

if TYPE_CHECKING:
    from ..run.supervisor.supervisor import Supervisor

DISCOVERY_WAIT = 3.0
"""A bridge made for this request waits at most this for the launch's nodes to show up:
a graph read a moment after joining would be empty."""
PUBLISHER_WAIT = 5.0
"""How long `hz` and `echo` wait for a topic's first publisher."""
NODE_WAIT = 5.0
"""How long a request for a node waits for it to appear on the graph: a node just started
again (a relaunch, a restart) is discovered within it on a busy machine (2 s was short once
for an rclpy talker, with the test suite on both cores)."""
SERVICE_TIMEOUT = 5.0
"""How long a node may take to answer a parameter or logger request."""


class Inspector(Plugin):
    def __init__(self, supervisor: Supervisor, ros: RosActions) -> None:
        self.supervisor = supervisor
        self.ros = ros
        self.clients: Clients | None = None
        self.find_process: Callable[[str], str] | None = None
        self.bridge_lock = asyncio.Lock()
        self.discovered = False
        self.reported = ReportedNames()
        self.unnamed: tuple[object, set[str]] = (None, set())  # (plan, its unnamed nodes)
        self.qos = QosWatch(self.qos_problems, self.send)
        hooks = StreamHooks(self.bridge, self.publisher_problem, self._subscribed, self.send,
                            PUBLISHER_WAIT)
        self.echoes = EchoStreams(hooks)
        self.plots = PlotStreams(hooks)
        self.hz = HzStreams(hooks)
        self.rates = RateWatch(hooks, lambda: self.ros.made)
        # the Services and Params tabs' requests
        self.graph = GraphRequests(self.bridge, self.current_name, SERVICE_TIMEOUT)
        supervisor.subscribe(self.learn_names)

    def learn_names(self, event: Event) -> None:
        """Learns the node name a process reports in its log lines, for the nodes the launch
        file does not name: stops reading a process's lines once one is known, and starts
        again when the process starts again (a relaunch may have moved it)."""
        if isinstance(event, Started) and event.process is not None:
            self.reported.forget(event.process)
            return
        if not isinstance(event, Output) or event.process is None or \
                self.reported.get(event.process):
            return
        plan = self.supervisor.plan
        if self.unnamed[0] is not plan:  # a relaunch replaced the plan
            self.unnamed = (plan, {p.id for p in plan.processes
                                   if p.kind == "node" and not p.full_name})
        if event.process in self.unnamed[1]:
            self.reported.add_lines(event.process, event.lines)

    # --- the plugin's hooks ------------------------------------------------------------------

    def serve(self, clients: Clients) -> None:
        self.clients = clients

    def handlers(self, find_process: Callable[[str], str]) -> Handlers:
        self.find_process = find_process
        handlers: dict[type[Request[Any]], Handler] = {
            Topics: self.topics, ParamsDump: self.params_dump, ParamsLoad: self.params_load,
            LogLevel: self.log_level}
        for part in (self.hz, self.rates, self.echoes, self.plots, self.qos, self.graph):
            handlers.update(part.handlers())
        return handlers

    def client_gone(self, client: int) -> None:
        for streams in (self.qos, self.echoes, self.plots, self.hz, self.rates):
            streams.client_gone(client)

    async def close(self) -> None:
        for streams in (self.hz, self.echoes, self.plots, self.qos, self.rates):
            await streams.close()

    # --- shared ------------------------------------------------------------------------------

    async def bridge(self) -> Any:
        """The launch's bridge; made now if need be, and then given a moment to discover the
        launch's nodes."""
        async with self.bridge_lock:
            made = self.ros.made is None
            try:
                bridge = await asyncio.to_thread(self.ros.bridge) if made else self.ros.made
            except RosError as exc:
                raise LaunchError(f"ROS is not available: {exc}") from None
            except ImportError as exc:  # rclpy not installed where the session runs
                raise LaunchError(f"ROS is not available here: {exc}") from None
            if made and not self.discovered:
                self.discovered = True
                await self.wait_discovery(bridge)
            return bridge

    async def wait_discovery(self, bridge: Any) -> None:
        wanted = {name for name, process in self.node_processes().items()
                  if self.supervisor.states.get(process) == "running"}
        loop = asyncio.get_running_loop()
        deadline = loop.time() + DISCOVERY_WAIT
        while loop.time() < deadline:
            if wanted <= set(await bridge.list_nodes()):
                return
            await asyncio.sleep(0.1)

    def node_processes(self) -> dict[str, str]:
        """`{full node name: process id}` for the plan's nodes, containers and components."""
        found: dict[str, str] = {}
        for proc in self.supervisor.plan.processes:
            if proc.kind in ("node", "container") and proc.full_name:
                found[proc.full_name] = proc.id
            elif proc.kind == "node":
                for name in self.reported.get(proc.id):
                    found.setdefault(name, proc.id)
            for component in proc.components:
                if component.get("full_name"):
                    found[str(component["full_name"])] = proc.id
        return found

    def process_named(self, node: str) -> str | None:
        """The one process whose log lines reported this full node name (a node the launch
        file does not name), for `wait`, `logs`, `restart` as for a process id."""
        owners = [process for process, names in self.reported.names.items() if node in names]
        return owners[0] if len(owners) == 1 else None

    def node_name(self, ref: Any) -> str:
        """A node given as its full name or its process id (or the launch's node name)."""
        if not isinstance(ref, str) or not ref:
            raise ValueError("a node is needed: its full name (/ns/name) or its process id")
        assert self.find_process is not None
        try:
            process = self.find_process(ref)
        except LaunchError:
            if ref.startswith("/"):
                return ref  # a node of the graph outside this launch
            raise LaunchError(f"no node or process {ref!r} in this launch "
                              f"(a node outside it is named by its full name, /ns/name)")\
                from None
        names = [name for name, owner in self.node_processes().items() if owner == process]
        if ref in names:
            return ref
        if len(names) != 1:
            raise LaunchError(f"process {process} runs no single named ROS node: "
                              f"give the node's full name (/ns/name)")
        return names[0]

    async def current_name(self, ref: Any) -> str:
        """`node_name`, waiting a moment for a process that has just started again (a
        relaunch, a restart, a respawn) to say its name in its first log line."""
        loop = asyncio.get_running_loop()
        deadline = loop.time() + NODE_WAIT
        while True:
            try:
                return self.node_name(ref)
            except LaunchError:
                process = self.process_of(ref)
                if process is None or self.reported.get(process) or loop.time() > deadline \
                        or self.supervisor.states.get(process) != "running":
                    raise
            await asyncio.sleep(0.1)

    def process_of(self, ref: Any) -> str | None:
        assert self.find_process is not None
        try:
            return self.find_process(str(ref))
        except LaunchError:
            return None

    async def require_node(self, bridge: Any, node: str) -> None:
        loop = asyncio.get_running_loop()
        deadline = loop.time() + NODE_WAIT
        while node not in await bridge.list_nodes():
            if loop.time() > deadline:
                raise LaunchError(f"no node {node} on the ROS graph")
            await asyncio.sleep(0.1)

    async def publisher_problem(self, bridge: Any, topic: str) -> str:
        """Why a topic cannot be measured: it does not exist, or nobody publishes it."""
        names = await asyncio.to_thread(bridge.node.get_topic_names_and_types)
        if topic not in {name for name, _ in names}:
            return f"no topic {topic} on the ROS graph"
        return f"topic {topic} has no publisher"

    # --- topics ------------------------------------------------------------------------------

    async def topics(self, request: Topics, client: int = 0) -> dict[str, Any]:
        node = request.node
        only = await self.current_name(node) if node else None
        bridge = await self.bridge()
        if only is not None:
            await self.require_node(bridge, only)
        result: dict[str, Any] = await bridge.topics(self.node_processes(), only)
        if request.problems_only:  # the TUI's QoS check: a few bytes, not the graph
            result["topics"] = [t for t in result.get("topics") or [] if t.get("qos_problems")]
        return result

    async def qos_problems(self) -> Problems:
        """What `watch_qos` checks: the topics with QoS problems; none for a launch without
        a node, for which ROS is not started."""
        if not any(p.kind in ("node", "container") for p in self.supervisor.plan.processes):
            return []
        topics: Problems = (await self.topics(Topics(problems_only=True))).get("topics") or []
        return topics

    def send(self, event: Event, client: int) -> None:
        if self.clients is not None:
            self.clients.send(event, client)

    def _subscribed(self, client: int) -> bool:
        return self.clients is not None and self.clients.subscribed(client)

    # --- parameters and loggers --------------------------------------------------------------

    async def params_dump(self, request: ParamsDump, client: int) -> dict[str, Any]:
        node = await self.current_name(request.node)
        bridge = await self.bridge()
        await self.require_node(bridge, node)
        try:
            return {"yaml": await bridge.dump_params(node, SERVICE_TIMEOUT)}
        except RosError as exc:
            raise LaunchError(f"{node} does not answer: {exc}") from None

    async def params_load(self, request: ParamsLoad, client: int) -> dict[str, Any]:
        from .param_files import load_values, text_values

        node = await self.current_name(request.node)
        values = text_values(request.yaml, node, request.source or "<yaml>")
        bridge = await self.bridge()
        await self.require_node(bridge, node)
        try:
            results = await load_values(bridge, node, values, SERVICE_TIMEOUT)
        except RosError as exc:
            raise LaunchError(f"{node} does not answer: {exc}") from None
        return {"results": [{"name": r.name, "ok": r.successful, "reason": r.reason}
                            for r in results]}

    async def log_level(self, request: LogLevel, client: int) -> dict[str, Any]:
        from .loggers import NoLoggerService, level_number

        ref = request.node
        node = await self.current_name(ref)
        level = request.level
        try:
            level_number(level)
        except RosError as exc:
            raise ValueError(str(exc)) from None
        bridge = await self.bridge()
        await self.require_node(bridge, node)
        try:
            await bridge.set_logger_level(node, level, SERVICE_TIMEOUT)
        except NoLoggerService:
            process = self.node_processes().get(node)
            how = (f"restart {process} with --log-level {level.upper()} to apply it"
                   if process else "only a restart with --ros-args --log-level changes it")
            raise LaunchError(f"{node} has no logger service (it was not created with "
                              f"enable_logger_service=True): {how}") from None
        except RosError as exc:
            raise LaunchError(f"{node}: {exc}") from None
        return {"ok": True}


__all__ = ["Inspector"]
