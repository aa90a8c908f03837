"""Moving between the tabs and out of text fields."""

from __future__ import annotations

from collections.abc import Callable

from textual.widget import Widget
from textual.widgets import Button, Input, OptionList, TabPane

from .screens.dialogs import HelpScreen
from .screens.fields import Field
from .session_link import SessionLink
from .tab_panels import TabPanels

OPENED_BY_KEY = frozenset({"search-input", "filter-input", "tpc-filter", "svc-filter",
                           "prm-filter"})
"""Fields a key opens (`/`, `\\`): leaving one goes back to where that key was typed."""


class Navigation:
    """Tabs and focus, keyboard first: the tab keys, escape out of a field, and where each
    tab puts the cursor. An object the app holds (`app.navigation`); `tab_shown` (the
    inspector's) is told of each tab that comes on screen; `panels` makes the Services,
    Params and Topics panels the first time their tab is shown (tab_panels.py)."""

    FILTERS = {"services": "#svc-filter", "params": "#prm-filter"}
    """The tabs whose list has a filter field that `/` opens (Nodes and Topics bind `/`)."""

    def __init__(self, app: SessionLink, tab_shown: Callable[[str], None],
                 panels: TabPanels) -> None:
        self.app = app
        self.tab_shown = tab_shown
        self.panels = panels
        self.left_for_field: Widget | None = None
        """The widget the user was on before going into a text field: escape and enter in a
        search or filter field go back there."""

    def tab(self, tab: str) -> None:
        """A tab key (1-5), `o`, the palette: the tab on screen once its panel is there (made
        now the first time: the tab switches when it is mounted, the keys typed meanwhile
        wait for it), where its work starts."""
        app = self.app
        if app.tabs.active != tab:
            self.panels.make(tab, lambda: self._switch(tab))
        app.refresh_bindings()

    def _switch(self, tab: str) -> None:
        app = self.app
        if app.tabs.active != tab:
            app.tabs.active = tab
            self._enter_tab(tab)
            app.refresh_bindings()

    def focused(self, widget: Widget) -> None:
        """A widget took the focus (the app's DescendantFocus)."""
        if not isinstance(widget, Input):
            self.left_for_field = widget

    def find(self) -> None:
        """`/` in the Services and Params tabs: into the list's filter field."""
        selector = self.FILTERS.get(self.app.tabs.active)
        if selector is not None:
            self.app.screen.set_focus(self.app.query_one(selector, Field))

    def leave_field(self) -> None:
        """Escape in a text field: out of it, back where the user was before it (the tree
        after `/` or `\\`), else to where the tab's work starts, so the next keys (1-5, s,
        q, ...) are commands again. The focus moves at once, not on the next tick, so keys
        typed right after escape go to the new place."""
        app = self.app
        focused = app.focused
        if isinstance(focused, Field) and focused.id in ("search-input", "filter-input"):
            app.output_panel.action_clear_search()
        before = self.left_for_field
        if isinstance(focused, Field) and focused.id in OPENED_BY_KEY and \
                isinstance(before, Widget) and before.is_attached and before.focusable \
                and before.screen is app.screen and pane_of(before) == pane_of(focused):
            app.screen.set_focus(before)
            return
        app.screen.set_focus(self._home(app.tabs.active))

    def _home(self, pane: str) -> Widget:
        """Where a tab's work starts: never a text field, so that the tab keys, q and the
        tab's own keys work as soon as the tab is shown (a field is entered with tab, `/`
        or a click)."""
        # in the tabs, not the screen on top: a dialog may have come up while a panel was made
        tabs = self.app.tabs
        if pane == "args":
            return tabs.query_one("#apply", Button)
        if pane == "services":
            return tabs.query_one("#svc-list", OptionList)
        if pane == "params":
            return tabs.query_one("#prm-nodes", OptionList)
        if pane == "topics":
            return tabs.query_one("#tpc-table")
        return self.app.launch_tree

    def tab_activated(self, pane: str) -> None:
        """A tab came on screen (TabbedContent.TabActivated: a key's, or a click's)."""
        self.app.refresh_bindings()
        if not self.panels.ready(pane):  # a click on a tab never shown: its panel first
            self.panels.make(pane, lambda: self._now_shown(pane))
            return
        self._now_shown(pane)

    def _now_shown(self, pane: str) -> None:
        """The tab is on screen with its panel: what it measures starts, the cursor in it."""
        if self.app.tabs.active != pane:
            return  # another tab was picked while this one's panel was made
        self.shown(pane)
        focused = self.app.focused
        if not (isinstance(focused, Widget) and pane_of(focused) == pane):
            self._enter_tab(pane)  # a click on a tab: the keys did this already

    def shown(self, pane: str) -> None:
        """A tab is on screen: what it measures starts, what the others did stops."""
        self.tab_shown(pane)
        self.app.args_tab.set_shown(pane == "args")

    def _enter_tab(self, pane: str) -> None:
        """Keyboard first: each tab puts the cursor where work starts, at once, so keys
        typed right after the tab key go there; again once the tab is laid out."""
        app = self.app
        if pane in ("services", "params"):
            self.panels.refresh_listing(pane)
        target = self._home(pane)
        app.tabs.screen.set_focus(target)
        app.call_after_refresh(self._refocus, pane, target)

    def _refocus(self, pane: str, target: Widget) -> None:
        app = self.app
        if not app.is_running or not app.screen_stack:
            return
        if app.screen is not target.screen:
            return  # a dialog came up meanwhile (q right after the tab key): it keeps the keys
        if app.tabs.active == pane and app.focused is not target and not (
                isinstance(app.focused, Widget) and pane_of(app.focused) == pane):
            app.screen.set_focus(target)

    def help(self) -> None:
        self.app.push_screen(HelpScreen())


def pane_of(widget: Widget) -> str | None:
    """The id of the tab pane a widget is in."""
    for node in widget.ancestors_with_self:
        if isinstance(node, TabPane):
            return node.id
    return None
