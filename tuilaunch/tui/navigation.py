"""Moving between the tabs and out of text fields."""

from __future__ import annotations

from textual import events, on
from textual.screen import ModalScreen
from textual.widget import Widget
from textual.widgets import Button, OptionList, TabbedContent, TabPane

from .key_order import reroute_key
from .screens.dialogs import HelpScreen
from .screens.fields import Field, after_escape
from .screens.params_panel import ParamsPanel
from .screens.services_panel import ServicesPanel
from .session_link import SessionLink


class Navigation(SessionLink):
    """Tabs and focus, keyboard first: the tab keys, escape out of a field, and where each
    tab puts the cursor."""

    def action_tab(self, tab: str) -> None:
        if self.tabs.active != tab:
            self.tabs.active = tab
            self._enter_tab(tab)
        self.refresh_bindings()

    def on_key(self, event: events.Key) -> None:
        """ESC and a key read together arrive as one key (see fields.py): outside a field,
        where escape leaves nothing, that is the key alone. Not in a dialog: there escape
        answers no, and the key must not answer again."""
        following = after_escape(event)
        if following is None or isinstance(self.screen, ModalScreen):
            return
        event.stop()
        if following.key in ("1", "2", "3", "4", "5"):
            self.action_tab(("nodes", "args", "services", "params", "topics")[
                int(following.key) - 1])
        else:
            reroute_key(self, following)

    def action_leave_field(self) -> None:
        """Escape in a text field: out of it, to where the tab's work starts, so the next
        keys (1-4, s, q, ...) are commands again. The focus moves at once, not on the next
        tick, so keys typed right after escape go to the new place."""
        focused = self.focused
        if isinstance(focused, Field) and focused.id in ("search-input", "filter-input"):
            self.output_panel.action_clear_search()
            self.screen.set_focus(self.output_panel.line_view)
            return
        self.screen.set_focus(self._home(self.tabs.active))

    def _home(self, pane: str) -> Widget:
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
        target: Widget | None = None
        if pane == "nodes":
            target = self.launch_tree
        elif pane == "args":
            editors = self.args_panel.query(".arg-editor")
            target = editors.first() if editors else self.query_one("#apply", Button)
        elif pane == "services":
            self.query_one(ServicesPanel).refresh_services()
            target = self.query_one("#svc-filter")
        elif pane == "params":
            self.query_one(ParamsPanel).refresh_nodes()
            target = self.query_one("#prm-filter")
        elif pane == "topics":
            target = self.query_one("#tpc-table")
        if target is not None:
            self.screen.set_focus(target)
            self.call_after_refresh(self._refocus, pane, target)

    def _refocus(self, pane: str, target: Widget) -> None:
        if not self.is_running or not self.screen_stack:
            return
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
