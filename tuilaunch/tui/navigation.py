"""Moving between the tabs and out of text fields."""

from __future__ import annotations

from textual import events, on
from textual.widget import Widget
from textual.widgets import Button, Input, OptionList, TabbedContent, TabPane

from .screens.dialogs import HelpScreen
from .screens.fields import Field
from .screens.params_panel import ParamsPanel
from .screens.services_panel import ServicesPanel
from .session_link import SessionLink

OPENED_BY_KEY = frozenset({"search-input", "filter-input", "tpc-filter", "svc-filter",
                           "prm-filter"})
"""Fields a key opens (`/`, `\\`): leaving one goes back to where that key was typed."""


class Navigation(SessionLink):
    """Tabs and focus, keyboard first: the tab keys, escape out of a field, and where each
    tab puts the cursor."""

    def action_tab(self, tab: str) -> None:
        if self.tabs.active != tab:
            self.tabs.active = tab
            self._enter_tab(tab)
        self.refresh_bindings()

    FILTERS = {"services": "#svc-filter", "params": "#prm-filter"}
    """The tabs whose list has a filter field that `/` opens (Nodes and Topics bind `/`)."""

    _left_for_field: Widget | None = None
    """The widget the user was on before going into a text field: escape and enter in a
    search or filter field go back there."""

    def on_descendant_focus(self, event: events.DescendantFocus) -> None:
        if not isinstance(event.widget, Input):
            self._left_for_field = event.widget

    def action_find(self) -> None:
        """`/` in the Services and Params tabs: into the list's filter field."""
        selector = self.FILTERS.get(self.tabs.active)
        if selector is not None:
            self.screen.set_focus(self.query_one(selector, Field))

    def action_leave_field(self) -> None:
        """Escape in a text field: out of it, back where the user was before it (the tree
        after `/` or `\\`), else to where the tab's work starts, so the next keys (1-5, s,
        q, ...) are commands again. The focus moves at once, not on the next tick, so keys
        typed right after escape go to the new place."""
        focused = self.focused
        if isinstance(focused, Field) and focused.id in ("search-input", "filter-input"):
            self.output_panel.action_clear_search()
        before = self._left_for_field
        if isinstance(focused, Field) and focused.id in OPENED_BY_KEY and \
                isinstance(before, Widget) and before.is_attached and before.focusable \
                and before.screen is self.screen and pane_of(before) == pane_of(focused):
            self.screen.set_focus(before)
            return
        self.screen.set_focus(self._home(self.tabs.active))

    def _home(self, pane: str) -> Widget:
        """Where a tab's work starts: never a text field, so that the tab keys, q and the
        tab's own keys work as soon as the tab is shown (a field is entered with tab, `/`
        or a click)."""
        if pane == "args":
            return self.query_one("#apply", Button)
        if pane == "services":
            return self.query_one("#svc-list", OptionList)
        if pane == "params":
            return self.query_one("#prm-nodes", OptionList)
        if pane == "topics":
            return self.query_one("#tpc-table")
        return self.launch_tree

    @on(TabbedContent.TabActivated)
    def _tab_changed(self, event: TabbedContent.TabActivated) -> None:
        self.refresh_bindings()
        pane = event.pane.id or "nodes"
        self.tab_shown(pane)
        focused = self.focused
        if not (isinstance(focused, Widget) and pane_of(focused) == pane):
            self._enter_tab(pane)  # a click on a tab: the keys did this already

    def _enter_tab(self, pane: str) -> None:
        """Keyboard first: each tab puts the cursor where work starts, at once, so keys
        typed right after the tab key go there; again once the tab is laid out."""
        if pane == "services":
            self.query_one(ServicesPanel).refresh_listing()
        elif pane == "params":
            self.query_one(ParamsPanel).refresh_listing()
        target = self._home(pane)
        self.screen.set_focus(target)
        self.call_after_refresh(self._refocus, pane, target)

    def _refocus(self, pane: str, target: Widget) -> None:
        if not self.is_running or not self.screen_stack:
            return
        if self.screen is not target.screen:
            return  # a dialog came up meanwhile (q right after the tab key): it keeps the keys
        if self.tabs.active == pane and self.focused is not target and not (
                isinstance(self.focused, Widget) and pane_of(self.focused) == pane):
            self.screen.set_focus(target)

    def action_help(self) -> None:
        self.push_screen(HelpScreen())


def pane_of(widget: Widget) -> str | None:
    """The id of the tab pane a widget is in."""
    for node in widget.ancestors_with_self:
        if isinstance(node, TabPane):
            return node.id
    return None
