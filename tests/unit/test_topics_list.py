"""The Topics tab's list as a user moves through it while the graph changes under it: the
row they moved to stays theirs when a listing lands (issue 45's loaded runs: a topic that
came as the cursor moved sent it back to the row it left)."""

from __future__ import annotations

from typing import Any

from textual.app import App, ComposeResult

from tuilaunch.tui.screens.topics_panel import TopicsPanel


class Graph:
    """The topics a session lists, changed by the test between two listings."""

    def __init__(self, *names: str) -> None:
        self.names = list(names)

    async def __call__(self, request: Any) -> dict[str, Any]:
        return {"topics": [{"name": n, "types": ["std_msgs/msg/String"], "publishers": [],
                            "subscribers": []} for n in self.names]}


class Tab(App[None]):
    def __init__(self, graph: Graph) -> None:
        super().__init__()
        self.graph = graph

    def compose(self) -> ComposeResult:
        yield TopicsPanel(self.graph)


async def lands(panel: TopicsPanel, graph: Graph) -> None:
    """A listing's answer taken in the same turn of the loop (as `refresh_topics` takes it
    when the answer is there before the cursor's message is handled)."""
    answer = await graph(None)
    panel.entries = {t["name"]: t for t in answer["topics"]}
    panel._fill()


async def test_the_row_moved_to_stays_selected_when_a_listing_lands_at_once() -> None:
    graph = Graph("/chat", "/scan")
    app = Tab(graph)
    async with app.run_test(size=(80, 24)) as pilot:
        panel = app.query_one(TopicsPanel)
        panel.set_shown(True)
        panel.timer.pause()  # the listings come when the test says
        await app.workers.wait_for_complete()
        await pilot.pause()
        assert panel.shown == ["/chat", "/scan"] and panel.selected == "/chat"
        panel.table.focus()
        # a move, and a listing with two new topics above it before the move is handled
        panel.table.move_cursor(row=1)
        graph.names = ["/chat", "/parameter_events", "/rosout", "/scan"]
        await lands(panel, graph)
        await pilot.pause()
        assert panel.selected == "/scan"
        assert panel.shown[panel.table.cursor_row] == "/scan"
        assert panel.detail_text.startswith("/scan")
        # and the next key moves on from there, not from where the cursor was sent back to
        await pilot.press("up")
        assert panel.selected == "/rosout" and panel.detail_text.startswith("/rosout")
