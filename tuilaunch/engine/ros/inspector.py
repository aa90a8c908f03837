"""The inspector's session requests: topics, rates, echo, parameter files, logger levels.

A supervisor plugin (run/plugins.py) whose `handlers` the session server answers (the ops
are listed in run/protocol.py). It works through the launch's bridge (actions.py owns it)
and knows the plan, so graph endpoints are mapped to the launch's processes and a node may
be named by its process id.

Streams are per client: `watch_rates` measures the union of what the clients watch and
stops a topic when nobody watches it; `echo` runs one throttled stream per client and
topic (echo_streams.py); `plot` one stream of decimated points per client and topic
(plot/streams.py); `watch_qos` sends the graph's QoS problems when they change
(qos_watch.py). A client that disconnects loses its streams (`client_gone`).
"""

from __future__ import annotations

import asyncio
import contextlib
from collections import deque
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ..errors import LaunchError
from ..run.events import Event, Hz, Output, Rates, Started
from ..run.plugins import Clients, Handlers, Plugin
from ..run.vocabulary.reported_names import ReportedNames
from ..run.vocabulary.ros_requests import (
    EchoStart,
    EchoStop,
    HzMeasure,
    HzRead,
    HzWatch,
    LogLevel,
    ParamsDump,
    ParamsLoad,
    PlotFields,
    PlotStart,
    PlotStop,
    Topics,
    WatchQos,
    WatchRates,
)
from .actions import RosActions
from .graph.echo_streams import EchoStreams
from .graph.graph_requests import GraphRequests
from .graph.qos_watch import Problems, QosWatch
from .graph.topic_graph import topic_of
from .plot.streams import PlotStreams
from .ros_errors import RosError

if TYPE_CHECKING:
    from ..run.supervisor.supervisor import Supervisor

RATES_PERIOD = 1.0
"""Seconds between `rates` events to a watching client."""
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
MAX_WINDOW = 600.0
RATE_HISTORY = 300
"""Rates kept per watched topic, one a second: the Topics tab's last five minutes."""


class Inspector(Plugin):
    def __init__(self, supervisor: Supervisor, ros: RosActions) -> None:
        self.supervisor = supervisor
        self.ros = ros
        self.clients: Clients | None = None
        self.find_process: Callable[[str], str] | None = None
        self.rate_watch: dict[int, set[str]] = {}
        self.unmeasured: dict[str, str] = {}  # watched topics not measured yet: why
        self.rate_history: dict[str, deque[float | None]] = {}
        """A rate a second of each topic some client watches, for as long as one does: a
        client that starts watching it is sent the minutes before (`watch_rates`)."""
        self.rates_task: asyncio.Task[None] | None = None
        self.hz_streams: dict[tuple[int, str], tuple[asyncio.Task[None], Any]] = {}
        """`tuilaunch hz` clients' measures, by (client, topic): the task sending the
        figures, and the meter."""
        self.pending: set[asyncio.Task[None]] = set()
        self.bridge_lock = asyncio.Lock()
        self.discovered = False
        self.reported = ReportedNames()
        self.unnamed: tuple[object, set[str]] = (None, set())  # (plan, its unnamed nodes)
        self.qos = QosWatch(self.qos_problems, self.send)
        self.echoes = EchoStreams(self.bridge, self.publisher_problem, self._subscribed,
                                  self.send, PUBLISHER_WAIT)
        # the Services and Params tabs' requests
        self.graph = GraphRequests(self.bridge, self.current_name, SERVICE_TIMEOUT)
        self.plots = PlotStreams(self.bridge, self.publisher_problem, self._subscribed,
                                 self.send, PUBLISHER_WAIT)
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
        return {Topics: self.topics, HzMeasure: self.hz, WatchRates: self.watch_rates,
                HzWatch: self.hz_watch, HzRead: self.hz_read,
                EchoStart: self.echoes.echo, EchoStop: self.echoes.echo_stop,
                ParamsDump: self.params_dump, ParamsLoad: self.params_load,
                LogLevel: self.log_level, WatchQos: self.qos.watch,
                PlotStart: self.plots.plot, PlotStop: self.plots.plot_stop,
                PlotFields: self.plots.plot_fields, **self.graph.handlers()}

    def client_gone(self, client: int) -> None:
        self.qos.client_gone(client)
        self.echoes.client_gone(client)
        self.plots.client_gone(client)
        for key in [k for k in self.hz_streams if k[0] == client]:
            self.hz_streams.pop(key)[0].cancel()
        if self.rate_watch.pop(client, None) is not None:
            task = asyncio.ensure_future(self.update_rates())
            self.pending.add(task)  # kept until done: a bare task may be collected
            task.add_done_callback(self.pending.discard)

    async def close(self) -> None:
        for task in [*(t for t, _ in self.hz_streams.values()), self.rates_task]:
            if task is not None:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await task
        await self.echoes.close()
        await self.plots.close()
        self.hz_streams.clear()
        self.rate_watch.clear()
        await self.qos.close()
        bridge = self.ros.made
        if bridge is not None:
            await bridge.stop_rates()

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

    # --- topics and rates --------------------------------------------------------------------

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

    async def hz(self, request: HzMeasure, client: int) -> dict[str, Any]:
        from .graph.rates import RateMeter

        topic = topic_of(request.topic)
        window = request.window or 10.0
        if not 0 < window <= MAX_WINDOW:
            raise ValueError(f"window {window:g} s is out of range (0-{MAX_WINDOW:g} s)")
        bridge = await self.bridge()
        # its own meter: a client watching the same topic keeps its own window
        meter = RateMeter(bridge.node)
        try:
            try:
                await meter.start(topic, window, PUBLISHER_WAIT)
            except RosError:
                raise LaunchError(f"{await self.publisher_problem(bridge, topic)} "
                                  f"(waited {PUBLISHER_WAIT:g} s)") from None
            await asyncio.sleep(window)
            return meter.read(topic)[topic]
        finally:
            meter.stop_all()

    async def hz_watch(self, request: HzWatch, client: int) -> dict[str, Any]:
        """`tuilaunch hz`: the topic measured over its last `messages` messages (as ros2
        topic hz -w), its figures sent to the client as an "hz" event every `every` s until
        it leaves; `hz_read` gives them at once."""
        from .graph.rates import RateMeter

        topic = topic_of(request.topic)
        if self.clients is None or not self.clients.subscribed(client):
            raise LaunchError("hz sends its figures as events: subscribe first")
        messages = request.messages
        if messages < 1:
            raise ValueError(f"messages {messages!r} is not a positive number")
        every = request.every or 1.0
        bridge = await self.bridge()
        meter = RateMeter(bridge.node)
        try:
            await meter.start(topic, wait=PUBLISHER_WAIT, messages=messages)
        except RosError:
            meter.stop_all()
            raise LaunchError(f"{await self.publisher_problem(bridge, topic)} "
                              f"(waited {PUBLISHER_WAIT:g} s)") from None
        old = self.hz_streams.pop((client, topic), None)
        if old is not None:
            old[0].cancel()
        task = asyncio.ensure_future(self.stream_hz(meter, topic, client, every))
        self.hz_streams[(client, topic)] = (task, meter)
        return {}

    async def stream_hz(self, meter: Any, topic: str, client: int, every: float) -> None:
        try:
            while True:
                await asyncio.sleep(every)
                for result in meter.read(topic).values():
                    self.send(Hz(data=result), client)
        finally:
            meter.stop_all()
            entry = self.hz_streams.get((client, topic))
            if entry is not None and entry[0] is asyncio.current_task():
                del self.hz_streams[(client, topic)]

    async def hz_read(self, request: HzRead, client: int) -> dict[str, Any]:
        topic = topic_of(request.topic)
        entry = self.hz_streams.get((client, topic))
        if entry is None:
            raise LaunchError(f"{topic} is not measured for this client")
        result: dict[str, Any] = entry[1].read(topic)[topic]
        return result

    async def watch_rates(self, request: WatchRates, client: int) -> dict[str, Any]:
        topics = request.topics
        if not all(isinstance(t, str) for t in topics):
            raise ValueError("watch_rates needs topics as a list of names")
        if topics:
            self.rate_watch[client] = set(topics)
        else:
            self.rate_watch.pop(client, None)
        await self.update_rates()
        return {"unmeasured": {t: self.unmeasured[t] for t in topics if t in self.unmeasured},
                "history": {t: list(self.rate_history[t]) for t in topics
                            if t in self.rate_history}}

    async def update_rates(self) -> None:
        """Measures the union of the watched topics, no more; the ticker runs while any
        client watches."""
        wanted = set().union(*self.rate_watch.values()) if self.rate_watch else set()
        if not wanted:
            if self.rates_task is not None:
                self.rates_task.cancel()
                self.rates_task = None
            self.unmeasured.clear()
            self.rate_history.clear()
            if self.ros.made is not None:
                await self.ros.made.stop_rates()
            return
        bridge = await self.bridge()
        measured = set(bridge.rate_meter().measured())
        await bridge.stop_rates(sorted(measured - wanted))
        for topic in list(self.unmeasured):
            if topic not in wanted:
                del self.unmeasured[topic]
        for topic in list(self.rate_history):
            if topic not in wanted:
                del self.rate_history[topic]
        await self.start_missing(bridge, wanted - measured)
        if self.rates_task is None:
            self.rates_task = asyncio.ensure_future(self.tick_rates())

    async def start_missing(self, bridge: Any, topics: set[str]) -> None:
        from .messages import MessageError

        for topic in sorted(topics):
            try:
                await bridge.start_rates([topic], wait=0.0)
                self.unmeasured.pop(topic, None)
            except RosError:
                self.unmeasured[topic] = await self.publisher_problem(bridge, topic)
            except MessageError as exc:
                self.unmeasured[topic] = str(exc)

    async def tick_rates(self) -> None:
        while self.rate_watch:
            await asyncio.sleep(RATES_PERIOD)
            bridge = self.ros.made
            if bridge is None:
                continue
            if self.unmeasured:  # a publisher may have come since
                await self.start_missing(bridge, set(self.unmeasured))
            rates = await bridge.read_rates()
            for topic in set().union(*self.rate_watch.values()):
                self.rate_history.setdefault(topic, deque(maxlen=RATE_HISTORY)).append(
                    rates.get(topic, {}).get("rate_hz"))
            for client, topics in list(self.rate_watch.items()):
                data = {t: {"rate_hz": rates.get(t, {}).get("rate_hz"),
                            "bytes_per_s": rates.get(t, {}).get("bytes_per_s")}
                        for t in sorted(topics)}
                self.send(Rates(data=data), client)

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
