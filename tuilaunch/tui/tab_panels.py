"""The Services, Params and Topics tabs' panels, made the first time their tab is shown.

Most sessions never open tabs 3-5: their widgets (and their modules) cost the first frame
nothing until then (issue 45, pay for what you use). Navigation asks for a panel as its tab
comes on screen (`make`); the keys typed meanwhile wait (key_order.py's hold) until the
panel is mounted, so they reach it, as they would a panel made at start. Whatever reads a
panel before it exists copes: the inspector drops the Topics tab's readings (the panel asks
for its own once shown, so it shows current data), and `o` asks for a node's topics once the
panel is there.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any, cast

from textual.widget import Widget
from textual.widgets import TabPane

from .key_order import hold_keys
from .session_link import SessionLink

if TYPE_CHECKING:
    from ..client.inspect.session_graph import GraphCalls
    from .screens.topics_panel import TopicsPanel

LAZY_TABS = ("services", "params", "topics")
"""The tabs whose panel is made when first shown; the others are made at start."""


class TabPanels:
    """The lazy tabs' panels of one app: `ready(tab)` once mounted, `make(tab, then)` to have
    it (then `then()` runs, at once when it is there already). `graph()` is the session's
    graph (the Services and Params panels'), `inspect(request)` a session request."""

    def __init__(self, app: SessionLink, graph: Callable[[], GraphCalls],
                 inspect: Callable[[Any], Awaitable[Any]]) -> None:
        self.app = app
        self.graph = graph
        self.inspect = inspect
        self.made: dict[str, Widget] = {}
        """The panels made so far, by tab: mounted, or being mounted (`_waiting`)."""
        self._waiting: dict[str, list[Callable[[], None]]] = {}
        """What runs once a panel being mounted is there."""

    def ready(self, tab: str) -> bool:
        """The tab's panel is mounted (a tab made at start always is)."""
        return tab not in LAZY_TABS or (tab in self.made and tab not in self._waiting)

    def make(self, tab: str, then: Callable[[], None]) -> None:
        """The tab's panel, made and mounted into its pane if it is not yet; `then()` once it
        is. The keys typed meanwhile wait for it."""
        if self.ready(tab):
            then()
            return
        if tab in self._waiting:
            self._waiting[tab].append(then)
            return
        self._waiting[tab] = [then]
        panel = self._panel(tab)
        self.made[tab] = panel
        pane = self.app.tabs.get_pane(tab)
        assert isinstance(pane, TabPane)
        hold = hold_keys(self.app)
        mounted = pane.mount(panel)

        async def when_mounted() -> None:
            try:
                await mounted
            finally:
                waiting = self._waiting.pop(tab, [])
                if tab == "topics":  # what the inspector and the recordings write to
                    self.app.topics_panel = cast("TopicsPanel", panel)
            try:
                for callback in waiting:
                    callback()
            finally:
                # after the tab is laid out, its cursor placed (`_refocus`, after the refresh
                # too): a panel just mounted is not focusable before, and a key let go then
                # would reach the widget left (the tree's `/` searches the pane)
                self.app.call_after_refresh(hold.release)

        self.app.run_worker(when_mounted(), group="tab-panels", exit_on_error=False)

    def _panel(self, tab: str) -> Widget:
        """The tab's panel, its module imported now."""
        app = self.app
        if tab == "services":
            from .screens.services_panel import ServicesPanel

            graph = self.graph()  # made here, on the UI's thread, not by the panel's worker
            return ServicesPanel(lambda: graph, id="services-panel")
        if tab == "params":
            from .screens.params_panel import ParamsPanel

            graph = self.graph()
            return ParamsPanel(lambda: graph, lambda: app.session.plan,
                               reported=lambda: app.store.reported_names,
                               request=self.inspect, id="params-panel")
        from .screens.topics_panel import TopicsPanel

        return TopicsPanel(self.inspect, id="topics-panel")

    def refresh_listing(self, tab: str) -> None:
        """The Services or Params list asked again (the tab was entered)."""
        from .screens.graph_listing import GraphListing  # loaded with the panel's module

        panel = self.made.get(tab)
        if self.ready(tab) and isinstance(panel, GraphListing):
            panel.refresh_listing()
