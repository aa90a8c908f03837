"""The fleet TUI's per-session tabs: each session's Args, Services, Params and Topics
panels, the single TUI's own; the plot (`p`) over them all (plots.py). What a session's
Nodes keys do is its view's (session_view.py).

Each robot has its own file, arguments and ROS graph, so each session has its own ArgsTab,
ServicesPanel, ParamsPanel and TopicsPanel (the single-session TUI's widgets), acting on
its own session; a tab shows the panels of the session of the selected row (a
ContentSwitcher per tab), and the header says which. A member's panels keep what they
showed (an edited form, a service's form, a node's parameters) while another session is
selected; the Topics panel of a session not on screen has its rates and echo stopped, as
the single TUI stops them when its tab is left.
"""

from __future__ import annotations

from textual.app import ComposeResult
from textual.widget import Widget
from textual.widgets import ContentSwitcher

from ...client.inspect.session_graph import SessionGraph
from ...engine.run.events import Echo, Event, PlotSamples, Rates, Relaunched
from ..arguments import ArgsTab
from ..nodes.events import Batch
from ..screens.fields import Field
from ..screens.params_panel import ParamsPanel
from ..screens.services_panel import ServicesPanel
from ..screens.topics_panel import TopicsPanel
from ..session_view import SessionView
from .plots import FleetPlots

TABS = ("args", "services", "params", "topics")
"""The tabs whose panels are per session (Nodes is the fleet's own split)."""
FILTERS = {"services": "#svc-filter", "params": "#prm-filter", "topics": "#tpc-filter"}
HOMES = {"args": "#apply", "services": "#svc-list", "params": "#prm-nodes",
         "topics": "#tpc-table"}
"""Where each tab's work starts: never a text field, so the tab keys and q work at once."""


class SessionPanels:
    """One session's Args, Services, Params and Topics panels, acting on its session alone
    (through its view, their host)."""

    def __init__(self, member: SessionView, index: int) -> None:
        self.member = member
        ask = member.request
        self.args = ArgsTab(member, id=f"args-{index}")
        self.graph = SessionGraph(ask)
        self.services = ServicesPanel(lambda: self.graph, id=f"services-{index}")
        self.params = ParamsPanel(lambda: self.graph, lambda: member.session.plan,
                                  reported=lambda: member.store.reported_names,
                                  request=ask, id=f"params-{index}")
        self.topics = TopicsPanel(ask, id=f"topics-{index}")

    def panel(self, tab: str) -> Widget:
        return {"args": self.args, "services": self.services, "params": self.params,
                "topics": self.topics}[tab]


class FleetTabs:
    """The per-session tabs of a fleet TUI: which session's panels show, and what a tab
    does when it comes on screen."""

    def __init__(self, members: list[SessionView], plots: FleetPlots) -> None:
        self.plots = plots
        self.panels = {id(m): SessionPanels(m, i) for i, m in enumerate(members)}
        self.members = members
        self.active = "nodes"
        """The tab last shown (a click on a tab is told from its key by it)."""

    def of(self, member: SessionView) -> SessionPanels:
        return self.panels[id(member)]

    def compose(self, tab: str) -> ComposeResult:
        """The tab's switcher, every session's panel in it."""
        panels = [self.of(m).panel(tab) for m in self.members]
        yield ContentSwitcher(*panels, id=f"fleet-{tab}", initial=panels[0].id)

    def shown(self, tab: str, member: SessionView) -> None:
        """`tab` is on screen for `member` (the selected session): its panels show and
        refresh; the others' Topics stop measuring."""
        self.active = tab
        panels = self.of(member)
        if tab in TABS:
            switcher = panels.panel(tab).parent
            if isinstance(switcher, ContentSwitcher):
                switcher.current = panels.panel(tab).id
        for other in self.members:
            self.of(other).topics.set_shown(tab == "topics" and other is member)
            self.of(other).args.set_shown(tab == "args" and other is member)
        if tab == "services":
            panels.services.refresh_listing()
        elif tab == "params":
            panels.params.refresh_listing()

    def home(self, tab: str, member: SessionView) -> Widget | None:
        """Where the tab's work starts, for `member` (the selected session)."""
        selector = HOMES.get(tab)
        if selector is None:
            return None
        return self.of(member).panel(tab).query_one(selector)

    def filter_field(self, tab: str, member: SessionView) -> Field | None:
        selector = FILTERS.get(tab)
        if selector is None:
            return None
        return self.of(member).panel(tab).query_one(selector, Field)

    def followed(self, member: SessionView) -> None:
        """The member's session is followed (again): its Args tab shows its plan's form."""
        self.of(member).args.show_form()

    def news(self, member: SessionView, shown: Batch) -> None:
        """What a drain of the member's session changed (its view's `show_events`): the
        readings and relaunches for its tabs."""
        for event in [*shown.readings, *shown.relaunched]:
            self.event(member, event)

    def event(self, member: SessionView, event: Event) -> None:
        """An event of the member's session for its tabs: a reading (rates, echo) for its
        Topics panel; a relaunch, the new form in its Args tab (another client's: said)."""
        panels = self.of(member)
        if isinstance(event, Relaunched):
            if event.lines != member.own_relaunch:
                panels.args.show_form()
                panels.args.notify(f"{member.label}: relaunched by another client: "
                                   f"{' '.join(event.lines) or 'defaults'}")
            member.own_relaunch = None
            return
        topics = panels.topics
        if isinstance(event, PlotSamples):
            self.plots.add(event.data or {})
        elif isinstance(event, Rates):
            topics.show_rates(event.data or {})
        elif isinstance(event, Echo):
            topics.show_echo(event.data or {})

