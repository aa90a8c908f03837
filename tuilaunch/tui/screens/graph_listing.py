"""What the panels of the ROS graph (parameters, services) share: they list their part of the
graph the first time they are shown (asked of the session, where the nodes run: the TUI
never loads rclpy; the in-process launch of some tests starts its bridge then), ask again
every few seconds while shown (discovery takes seconds on a busy machine, and nodes come
and go: a restart, a relaunch that moves them), and a failed graph query is a line in the
panel, never the panel's end."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any, cast

from rich.text import Text
from textual import work
from textual.timer import Timer
from textual.widget import Widget
from textual.widgets import OptionList
from textual.widgets.option_list import Option

from ...client.inspect.session_graph import GraphCalls

RELIST_S = 2.0
"""While the Services or Params tab shows, its list is asked of the graph this often (a
local query, nothing on the network): a new participant discovers the others over seconds
on a busy machine, and nodes come and go."""


def discovering(noun: str, every: float) -> str:
    """What an empty list of the graph says: a graph seen too early looks empty."""
    return f"no {noun} yet, discovering (asked every {every:g} s)"


def refill(listing: OptionList, shown: list[str], title: str) -> bool:
    """Lists the names `shown` under `title`. The row the user was on stays highlighted
    (the list is asked again every few seconds): False when it is no longer shown."""
    highlighted = listing.highlighted
    was = None if highlighted is None or highlighted >= listing.option_count else \
        listing.get_option_at_index(highlighted).id
    listing.clear_options()
    listing.add_options([Option(Text(name, no_wrap=True, overflow="ellipsis"), id=name)
                         for name in shown])
    listing.border_title = title
    if was not in shown:
        return False
    listing.highlighted = shown.index(was)
    return True


class GraphListing:
    """Mixin of a graph panel (a Widget): `refresh_listing()` runs when the panel is first
    shown, again every RELIST_S while it shows (and on demand); it asks `graph()`
    (client/session_graph.py's GraphCalls) for `list_<listing>` and hands the answer to
    `show_listing`, or says why it failed with `report`."""

    graph: Callable[[], GraphCalls]
    listing = ""  # what is listed: "nodes" asks graph().list_nodes()
    listed = False  # the list was asked for (the tab was shown)
    answered = False  # the graph answered once
    failed = False  # the last listing failed, and the panel says why
    relist: Timer | None = None

    def show_listing(self, listing: Any, reload: bool) -> None:
        """`reload`: asked for by the user (Refresh, first look), not by the timer."""
        raise NotImplementedError

    def report(self, text: str, ok: bool) -> None:
        raise NotImplementedError

    def title(self, shown: int, term: str, noun: str, more: str = "") -> str:
        """A list's title: how many `noun`s it shows; while nothing is seen (no filter), that
        discovery goes on: a new participant sees the graph over seconds, and an empty list
        alone reads as "there is none"."""
        if shown or term:
            return f"{shown} {noun}{'' if shown == 1 else 's'}{more}"
        if not self.answered:
            return f"asking the ROS graph for {noun}s..."
        return discovering(noun, RELIST_S) + more

    def on_show(self) -> None:
        if not self.listed:
            self.listed = True
            self.refresh_listing()
        if self.relist is None:
            self.relist = cast(Widget, self).set_interval(RELIST_S, self._relist)
        self.relist.resume()

    def on_hide(self) -> None:
        if self.relist is not None:
            self.relist.pause()

    def _relist(self) -> None:
        # one listing slower than the period (rclpy's first start) is let finish, not replaced
        workers = cast(Widget, self).workers
        if not any(w.group == "graph-listing" and not w.is_finished for w in workers):
            self.refresh_listing(reload=False)

    @work(group="graph-listing", exclusive=True, exit_on_error=False)
    async def refresh_listing(self, reload: bool = True) -> None:
        try:
            graph = await asyncio.to_thread(self.graph)  # a bridge's start: off the UI loop
            listing = await getattr(graph, f"list_{self.listing}")()
        except Exception as exc:  # a graph query must never take the panel down
            self.report(f"cannot list {self.listing}: {exc}", ok=False)
            self.failed = True
            return
        self.answered = True
        if self.failed:  # why the last one failed is no longer true
            self.failed = False
            self.report("", ok=True)
        self.show_listing(listing, reload)
