"""The inspector's side of the app: session requests for the Topics tab, the params files
and logger levels; the server's `rates`, `echo` and `resources` events to their widgets;
sampling asked for only while its tab is on screen."""

from __future__ import annotations

import re
from collections import deque
from collections.abc import Callable, Coroutine
from functools import partial
from typing import TYPE_CHECKING, Any, TypeVar

from textual.binding import Binding
from textual.timer import Timer

from ...engine.run.events import Echo, Event, PlotSamples, Qos, Rates, Resources, Trend
from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.request import Request
from ...engine.run.vocabulary.requests import WatchQos, WatchResources
from ..session_link import SessionLink
from .log_levels import LogLevels
from .plots import open_plot
from .recording import Recordings

if TYPE_CHECKING:
    from ...client.inspect.session_graph import GraphCalls

R = TypeVar("R")

FIGURES_SETTLE = 0.3
"""Seconds the selection rests before the server is told whose CPU and memory to send."""
TREND_KEEP = 300
"""CPU and memory samples kept for the selected node's sparklines: one a second, 5 min."""


INSPECTOR_BINDINGS = [
    Binding("o", "inspector('node_topics')", "Topics of node", show=False,
            tooltip="The selected node's topics, in the Topics tab"),
    Binding("L", "inspector('log_level')", "Log level", show=False,
            tooltip="Set the selected node's log level"),
    Binding("b", "inspector('black_box')", "Black box", show=False,
            tooltip="Write the session's black box now (its log folder)"),
]
"""The inspector's keys, bound on the app (`action_inspector` hands them over by name)."""


class Inspector:
    """Topics, rates, echo, CPU and memory, log levels: all asked of the session server
    (where the nodes run) through the supervisor's `request`, on the engine thread. An
    object the app holds (`app.inspector`); `show_tab` shows a tab (`o`)."""

    def __init__(self, app: SessionLink, show_tab: Callable[[str], None]) -> None:
        self.app = app
        self.show_tab = show_tab
        self.watching_resources = False
        self._figures_asked: list[str] | None = None
        """The processes the server sends CPU and memory of (None: all), last asked."""
        self._figures_timer: Timer | None = None
        self.log_levels = LogLevels(app, self.inspect, app.asked_to_stop)
        self._graph: GraphCalls | None = None
        self.recordings = Recordings(app, self.inspect)  # w in the Topics tab, b
        self.trends: dict[str, deque[tuple[float, float]]] = {}
        """The selected process's (CPU%, RSS) a second, the server's last minutes first."""
        self._trend_asked: str | None = None
        self.plot_screen: Any = None
        """The plot on screen (screens/plot_screen.py, imported with the first plot)."""
        self.topics_process: str | None = None
        """The process whose node's topics `o` listed: the list follows the node when a
        relaunch or a restart moves it."""
        self._node_to_list: str | None = None
        """The node `o` asked for before the Topics tab was first shown: listed once its
        panel is there (tab_panels.py)."""

    @property
    def graph(self) -> GraphCalls:
        """The Services and Params tabs' graph: the session's, where the nodes run (this
        process never loads rclpy); made, and its module imported, when first used."""
        if self._graph is None:
            from ...client.inspect.session_graph import SessionGraph

            self._graph = SessionGraph(self.inspect)
        return self._graph

    async def inspect(self, request: Request[R]) -> R:
        """A session request's result; raises SessionError with the server's message."""
        return await self.app.engine.run(self.app.view.client().request(request))

    def show(self, event: Event) -> None:
        """A reading the session sent (rates, echo, plot samples, CPU and memory, QoS
        problems) to the widget that asked for it."""
        data = event.data or {}
        # the Topics tab's, once it was shown: before, it asked for none of them
        topics_panel = self.app.topics_panel
        if isinstance(event, Rates):
            if topics_panel is not None:
                topics_panel.show_rates(data)
        elif isinstance(event, Echo):
            if topics_panel is not None:
                topics_panel.show_echo(data)
        elif isinstance(event, PlotSamples):
            if self.plot_screen is not None:
                self.plot_screen.add(data)
        elif isinstance(event, Resources):
            if self.watching_resources:  # one sent before the server heard "off" is stale
                self.app.launch_tree.set_usage(data)
        elif isinstance(event, Trend):
            if self.watching_resources:
                for process, (cpu, rss) in data.items():
                    self.trends.setdefault(process, deque(maxlen=TREND_KEEP)).append(
                        (float(cpu or 0.0), float(rss or 0)))
        elif isinstance(event, Qos):
            # the server says when the problems change (watch_qos): the tree marks both
            # nodes of each pair that cannot talk, the line above it says why
            self.app.launch_tree.set_qos_problems(self.qos_problems_by_process(
                data.get("topics") or []))
            self.app.update_detail()

    def tab_shown(self, pane: str) -> None:
        """Measures what the tab on screen shows, and only that: rates and echo for the
        Topics tab, CPU and memory for the Nodes tab."""
        topics_panel = self.app.topics_panel
        if topics_panel is not None:  # made the first time its tab shows
            if pane == "topics" and self._node_to_list is not None:
                topics_panel.show_node(self._node_to_list)  # `o` before it was made
                self._node_to_list = None
            topics_panel.set_shown(pane == "topics")
        nodes = pane == "nodes"
        if nodes != self.watching_resources and self.app.supervisor is not None:
            self.watching_resources = nodes
            self._start(partial(self._watch_resources, nodes))
            # the QoS marks: the server checks the graph and says when they change, so
            # an ssh link carries no request for marks that rarely change
            self._start(partial(self._watch, WatchQos(on=nodes)))

    def qos_problems_by_process(self, topics: list[dict[str, Any]]) -> dict[str, list[str]]:
        """Each launch process's node, and the QoS sentences that name it."""
        by_name = {self.node_name(p.id): p.id for p in self.app.session.plan.processes}
        found: dict[str, list[str]] = {}
        for topic in topics:
            problems = topic.get("qos_problems") or []
            if not problems:
                continue
            for endpoint in [*(topic.get("publishers") or []),
                             *(topic.get("subscribers") or [])]:
                node = str(endpoint.get("node") or "")
                process = endpoint.get("process") or by_name.get(node)
                if not process or not node:
                    continue
                named = re.compile(rf"(?<![\w/]){re.escape(node)}(?![\w/])")
                for problem in problems:
                    if named.search(problem) and problem not in found.get(process, []):
                        found.setdefault(process, []).append(problem)
        return found

    def _start(self, work: partial[Coroutine[Any, Any, None]]) -> None:
        """A request of the inspector's, in a worker. Given as a coroutine function, not a
        coroutine: a worker the closing app never starts leaves none unawaited."""
        # Textual runs a partial of a coroutine function (textual/worker.py) but its
        # annotation names plain callables only
        self.app.run_worker(work, group="inspector",  # type: ignore[arg-type]
                            exit_on_error=False)

    async def _watch_resources(self, on: bool) -> None:
        # no CPU column without it; of the processes whose figures are on screen only; and
        # the selected one's last minutes, for the sparklines of the detail line
        tree = self.app.launch_tree
        self._figures_asked = tree.figures_shown()
        selected = self.app.nodes.selected_process() if on else None
        self._trend_asked = selected
        try:
            result = await self.inspect(WatchResources(on=on, processes=self._figures_asked,
                                                       trend=[selected] if selected else []))
        except SessionError:
            return
        if on:
            kept = (result or {}).get("history") or {}
            self.trends = {p: deque(((float(c or 0.0), float(r or 0)) for c, r in samples),
                                    maxlen=TREND_KEEP) for p, samples in kept.items()}
        else:
            self.trends = {}
            tree.set_usage({})  # figures that no longer move would mislead
        self.app.update_detail()

    async def _watch(self, request: Request[Any]) -> None:
        """Starts or stops a stream of the server's (`watch_qos`); one the server cannot
        give leaves the tree as it was."""
        try:
            await self.inspect(request)
        except SessionError:
            pass

    def figures_follow(self) -> None:
        """The figures on screen are another process's (the selection moved), or every
        process's (the tree grew wide enough for its column): the server is told once the
        selection rests, so running down the tree is one request, not one a row."""
        if not self.watching_resources or not self._figures_moved():
            return
        if self._figures_timer is not None:
            self._figures_timer.stop()
        self._figures_timer = self.app.set_timer(FIGURES_SETTLE, self._ask_figures)

    def _figures_moved(self) -> bool:
        return self.app.launch_tree.figures_shown() != self._figures_asked or \
            self.app.nodes.selected_process() != self._trend_asked

    def _ask_figures(self) -> None:
        self._figures_timer = None
        if self.watching_resources and self._figures_moved():
            self._start(partial(self._watch_resources, True))

    # --- plots ------------------------------------------------------------------------------

    def plot(self, topic: str) -> None:
        self.app.run_worker(self._open_plot(topic), group="inspector", exit_on_error=False)

    async def _open_plot(self, topic: str) -> None:
        """The plot of `topic`; the screen asks its streams of the session itself (plot,
        plot_fields, topics, plot_stop), as `tuilaunch plot` and the fleet's do: this app
        hands it the events."""
        def leave() -> None:
            self.plot_screen = None
            self.app.pop_screen()

        self.plot_screen = await open_plot(self.app, self.inspect, topic, {"": self.inspect},
                                           "", leave)

    # --- from the Nodes tab ------------------------------------------------------------------

    def node_name(self, process: str) -> str:
        """The ROS name of a process's node: the plan's, else the one it reports."""
        return self.app.store.node_name(self.app.session.plan, process)

    def trend_of(self, process: str) -> deque[tuple[float, float]] | None:
        """A process's CPU and memory trend, while the Nodes tab measures them."""
        return self.trends.get(process) if self.watching_resources else None

    def applies(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """As Textual's check_action for the inspector's keys (`action` its name here)."""
        if action in ("node_topics", "log_level"):
            if self.app.supervisor is None or self.app.tabs.active != "nodes":
                return False
            return True if self.app.nodes.selected_process() is not None else None
        return True

    def act(self, action: str) -> None:
        {"node_topics": self.node_topics, "log_level": self.log_level,
         "black_box": lambda: self.app.run_worker(
             self.recordings.black_box_now(), group="recording", exit_on_error=False),
         "black_box_keep": lambda: self.app.run_worker(
             self.recordings.black_box_keep(), group="recording", exit_on_error=False),
         }[action]()

    def node_topics(self) -> None:
        process = self.app.nodes.selected_process()
        if process is None:
            return
        self.topics_process = process
        panel = self.app.topics_panel
        if panel is None:  # listed once the tab is first shown (`tab_shown`)
            self._node_to_list = self.node_name(process)
        else:
            panel.show_node(self.node_name(process))
        self.show_tab("topics")

    def detail_shown(self) -> None:
        """The detail line drew the selection again: what follows it follows."""
        self._follow_topics_node()
        self.figures_follow()  # the selection may have moved

    def _follow_topics_node(self) -> None:
        """After events: the node `o` listed may now be elsewhere (robot:=r1 -> r2)."""
        process = self.topics_process
        if process is None:
            return
        panel = self.app.topics_panel
        if panel is None or self._node_to_list is not None:
            return  # its tab not shown yet: the node is listed when it is
        if panel.node is None:
            self.topics_process = None  # `x` listed all topics: nothing to follow
            return
        name = self.node_name(process)
        if name not in (panel.node, process):  # known again, and somewhere else
            panel.show_node(name)

    def log_level(self) -> None:
        process = self.app.nodes.selected_process()
        if process is not None:
            self.log_levels.ask(process, self.node_name(process))
