"""The Params tab's node list when two nodes share a name (two launches on one ROS domain,
as `ros2 node list` shows them): each name is listed once, and the list says so. In a small
host app over a graph that answers as a session does."""

from __future__ import annotations

from textual.app import App, ComposeResult
from textual.widgets import OptionList

from tuilaunch.tui.screens.params_panel import ParamsPanel


class Graph:
    """The graph's node list as the session sends it: a name once per node."""

    def __init__(self, nodes: list[str]) -> None:
        self.nodes = nodes

    async def list_nodes(self) -> list[str]:
        return list(self.nodes)


class Host(App[None]):
    def __init__(self, graph: Graph) -> None:
        super().__init__()
        self.graph = graph

    def compose(self) -> ComposeResult:
        yield ParamsPanel(lambda: self.graph, lambda: None)  # type: ignore[arg-type, return-value]


async def listed(app: Host, pilot) -> list[str]:
    listing = app.query_one("#prm-nodes", OptionList)
    for _ in range(200):
        await pilot.pause(0.02)
        if listing.option_count:
            break
    return [str(listing.get_option_at_index(i).id) for i in range(listing.option_count)]


async def test_a_name_two_nodes_share_is_listed_once_and_said():
    graph = Graph(["/r1/talker", "/r1/talker", "/r1/listener"])
    app = Host(graph)
    async with app.run_test() as pilot:
        assert await listed(app, pilot) == ["/r1/talker", "/r1/listener"]
        title = str(app.query_one("#prm-nodes", OptionList).border_title)
        assert title == "2 nodes; 1 name shared by several nodes"
        # once the other launch is gone, the list says nothing more
        graph.nodes = ["/r1/talker", "/r1/listener"]
        app.query_one(ParamsPanel).refresh_listing()
        for _ in range(200):
            await pilot.pause(0.02)
            if "shared" not in str(app.query_one("#prm-nodes", OptionList).border_title):
                break
        assert str(app.query_one("#prm-nodes", OptionList).border_title) == "2 nodes"
