"""What the panels of the ROS graph (parameters, services) share: they list their part of the
graph the first time they are shown, so that rclpy starts in the UI only for someone who
looks, and a failed graph query is a line in the panel, never the panel's end."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from textual import work


class GraphListing:
    """Mixin of a graph panel: `refresh_listing()` runs when the panel is first shown (and on
    demand); it asks the bridge's `list_<listing>` and hands the answer to `show_listing`, or
    says why it failed with `report`."""

    bridge: Callable[[], Any]
    listing = ""  # what is listed: "nodes" asks bridge.list_nodes()
    listed = False  # the list was asked for (the tab was shown)

    def show_listing(self, listing: Any) -> None:
        raise NotImplementedError

    def report(self, text: str, ok: bool) -> None:
        raise NotImplementedError

    def on_show(self) -> None:
        if not self.listed:
            self.listed = True
            self.refresh_listing()

    @work(group="graph-listing", exclusive=True, exit_on_error=False)
    async def refresh_listing(self) -> None:
        try:
            bridge = await asyncio.to_thread(self.bridge)  # rclpy's start: off the UI loop
            listing = await getattr(bridge, f"list_{self.listing}")()
        except Exception as exc:  # a graph query must never take the panel down
            self.report(f"cannot list {self.listing}: {exc}", ok=False)
            return
        self.show_listing(listing)
