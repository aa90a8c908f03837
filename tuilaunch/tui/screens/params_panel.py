"""The parameter panel: live nodes, their parameters, edit, set, the node's answer; the
node's live parameters written to a params file, or a file loaded into it."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import yaml
from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import Button, DataTable, Input, OptionList, Static

from ...client.inspect.session_graph import GraphCalls
from ...engine.plan.model import Plan
from ...engine.ros.calls import ParameterInfo
from ...engine.run.vocabulary.requests import ParamsDump, ParamsLoad
from .dialogs import PathScreen
from .fields import Field
from .graph_listing import GraphListing, refill


def show_value(value: Any) -> str:
    if isinstance(value, str):
        return value
    return yaml.safe_dump(value, default_flow_style=True).strip().removesuffix("...").strip()


def parse_value(type_name: str, text: str) -> Any:
    """Text from the edit field in the parameter's declared type, or ValueError saying why."""
    if type_name == "str":
        return text
    if type_name == "bool":
        lowered = text.strip().lower()
        if lowered not in ("true", "false"):
            raise ValueError(f"needs true or false, got {text!r}")
        return lowered == "true"
    if type_name == "int":
        return int(text)
    if type_name == "float":
        return float(text)
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        raise ValueError(f"{text!r} is not a list like [1, 2]") from None
    if not isinstance(value, list):
        raise ValueError(f"needs a list like [1, 2], got {text!r}")
    if type_name == "float[]":
        return [float(v) for v in value]
    if type_name == "int[]":
        return [int(v) for v in value]
    if type_name == "bool[]":
        return [bool(v) for v in value]
    return [str(v) for v in value]


class ParamsPanel(GraphListing, Horizontal):
    DEFAULT_CSS = """
    ParamsPanel #prm-left { width: 30%; min-width: 26; max-width: 48;
                            border-right: tall $panel; }
    ParamsPanel #prm-right { width: 1fr; padding: 0 1; }
    ParamsPanel #prm-table { height: 1fr; }
    ParamsPanel #prm-about { height: 2; color: $text-muted; }
    ParamsPanel #prm-edit-row { height: 3; }
    ParamsPanel #prm-edit { width: 1fr; }
    ParamsPanel #prm-result { height: auto; }
    ParamsPanel #prm-result.error { color: $error; }
    """
    BINDINGS = [
        Binding("w", "write_file", "Write file", tooltip="Write the node's live parameters "
                "to a params file a launch file can load"),
        Binding("o", "open_file", "Load file", tooltip="Set the node's parameters from a "
                "params file"),
    ]

    listing = "nodes"

    def __init__(self, graph: Callable[[], GraphCalls], plan: Callable[[], Plan],
                 timeout: float = 5.0,
                 reported: Callable[[], dict[str, set[str]]] | None = None,
                 request: Callable[..., Awaitable[Any]] | None = None,
                 **kwargs: object) -> None:
        """`graph()`: where the nodes' parameters are read and set (the session's);
        `request(request)`: a session request (params_dump, params_load), made where
        the nodes run."""
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.graph = graph
        self.request = request
        self.plan = plan
        self.reported = reported or dict
        self.timeout = timeout
        self.nodes: list[str] = []
        self.shared: list[str] = []
        """Names more than one node of the graph has (each listed once)."""
        self.node: str | None = None
        self.params: dict[str, ParameterInfo] = {}
        self.current: str | None = None

    def compose(self) -> ComposeResult:
        with Vertical(id="prm-left"):
            yield Field(placeholder="filter nodes", id="prm-filter")
            yield OptionList(id="prm-nodes")
            yield Button("Refresh", id="prm-refresh")
        with Vertical(id="prm-right"):
            yield DataTable(id="prm-table", cursor_type="row", zebra_stripes=True)
            yield Static("Pick a node, then a parameter.", id="prm-about")
            with Horizontal(id="prm-edit-row"):
                yield Field(placeholder="new value (enter sets it)", id="prm-edit")
                yield Button("Set", id="prm-set", variant="primary")
            yield Static("", id="prm-result")

    def on_mount(self) -> None:
        table = self.query_one(DataTable)
        # the value beside what the launch file gave: the comparison fits 80 columns
        for key, title in (("name", "name"), ("value", "value"), ("launch", "launch file"),
                           ("type", "type"), ("ro", "ro")):
            table.add_column(title, key=key)
        self.query_one("#prm-nodes", OptionList).border_title = self.title(0, "", "node")

    def show_listing(self, listing: list[str], reload: bool) -> None:
        # two nodes of one name (two launches on one ROS domain): listed once, and said, as
        # `ros2 node list` warns; their parameters are whichever answers
        unique = list(dict.fromkeys(listing))
        shared = sorted({n for n in unique if listing.count(n) > 1})
        if unique != self.nodes or shared != self.shared or \
                not self.query_one("#prm-nodes", OptionList).option_count:
            self.nodes, self.shared = unique, shared
            self._fill_nodes()
        if reload and self.node is not None:
            self.load_node(self.node)

    @on(Input.Changed, "#prm-filter")
    def _fill_nodes(self) -> None:
        term = self.query_one("#prm-filter", Input).value.lower()
        shown = [n for n in self.nodes if term in n.lower()]
        shared = len(self.shared)
        refill(self.query_one("#prm-nodes", OptionList), shown, self.title(
            len(shown), term, "node",
            f"; {shared} name{'s' if shared > 1 else ''} shared by several nodes"
            if shared else ""))

    @on(Input.Submitted, "#prm-filter")
    def _filter_submitted(self) -> None:
        listing = self.query_one("#prm-nodes", OptionList)
        if listing.option_count:
            self.load_node(str(listing.get_option_at_index(0).id))
            self.query_one(DataTable).focus()

    @on(Button.Pressed, "#prm-refresh")
    def _refresh(self) -> None:
        self.refresh_listing()

    @on(OptionList.OptionSelected, "#prm-nodes")
    def _picked(self, event: OptionList.OptionSelected) -> None:
        self.load_node(str(event.option.id))

    def launch_values(self, node: str) -> dict[str, Any]:
        """Parameters the launch file gave this node (inline ones; files are the user's).

        A node named by its own code has no name in the plan: it is matched by the name
        its process reports in its log lines."""
        processes = self.plan().processes
        for proc in processes:
            if proc.full_name == node:
                return proc.parameters
        reported = self.reported()
        for proc in processes:
            if proc.full_name is None and node in reported.get(proc.id, ()):
                return proc.parameters
        return {}

    @work(group="params-load", exclusive=True, exit_on_error=False)
    async def load_node(self, node: str, announce: bool = True) -> None:
        self.node = node
        try:
            described = await self.graph().describe_parameters(node, timeout=self.timeout)
        except Exception as exc:  # timeouts, vanished nodes: shown, never raised
            self.show_result(f"{node}: {exc}", ok=False)
            return
        self.params = {p.name: p for p in described}
        launch = self.launch_values(node)
        table = self.query_one(DataTable)
        table.clear()
        for info in described:
            from_launch = show_value(launch[info.name]) if info.name in launch else ""
            table.add_row(info.name, show_value(info.value), from_launch, info.type,
                          "yes" if info.read_only else "", key=info.name)
        if announce:  # not over the answer of a params file just loaded
            self.show_result(f"{node}: {len(described)} parameters", ok=True)

    @on(DataTable.RowHighlighted)
    def _highlighted(self, event: DataTable.RowHighlighted) -> None:
        name = str(event.row_key.value)
        info = self.params.get(name)
        if info is None:
            return
        self.current = name
        about = info.description or "(no description)"
        if info.constraints:
            about += f"  ({info.constraints})"
        if info.read_only:
            about += "  read-only"
        self.query_one("#prm-about", Static).update(Text(f"{name} [{info.type}]: {about}"))
        self.query_one("#prm-edit", Input).value = show_value(info.value)

    @on(DataTable.RowSelected, "#prm-table")
    def _row_entered(self, event: DataTable.RowSelected) -> None:
        """Enter on a parameter: into its value's field, to edit and set it."""
        if str(event.row_key.value) in self.params:
            edit = self.query_one("#prm-edit", Input)
            edit.focus()
            edit.select_all()

    @on(Button.Pressed, "#prm-set")
    @on(Input.Submitted, "#prm-edit")
    def _set(self) -> None:
        self.set_current(self.query_one("#prm-edit", Input).value)

    @work(group="params-set", exclusive=True, exit_on_error=False)
    async def set_current(self, text: str) -> None:
        if self.node is None or self.current is None:
            self.show_result("pick a node and a parameter first", ok=False)
            return
        node, name = self.node, self.current
        info = self.params[name]
        try:
            value = parse_value(info.type, text)
        except ValueError as exc:
            self.show_result(f"{name} ({info.type}) {exc}", ok=False)
            return
        try:
            (result,) = await self.graph().set_parameters(node, {name: value},
                                                          timeout=self.timeout)
            now = await self.graph().get_parameters(node, [name], timeout=self.timeout)
        except Exception as exc:  # timeouts and vanished nodes are shown in the panel
            self.show_result(f"{node} {name}: {exc}", ok=False)
            return
        if result.successful:
            self.show_result(f"set {name} = {show_value(value)}; {node} now reports "
                             f"{show_value(now.get(name))}", ok=True)
            info.value = now.get(name)
            self.query_one(DataTable).update_cell(name, "value", show_value(info.value))
            # the next value typed replaces this one rather than being appended to it
            self.query_one("#prm-edit", Field).select_all()
        else:
            self.show_result(f"{node} refused {name} = {show_value(value)}: {result.reason}",
                             ok=False)

    def show_result(self, text: str, ok: bool) -> None:
        result = self.query_one("#prm-result", Static)
        result.update(Text(text))
        result.set_class(not ok, "error")

    report = show_result

    # --- params files ------------------------------------------------------------------------

    def _file_node(self) -> str | None:
        if self.request is None:
            self.show_result("params files need a session (tuilaunch FILE)", ok=False)
            return None
        if self.node is None:
            self.show_result("pick a node first (enter on its name)", ok=False)
        return self.node

    def action_write_file(self) -> None:
        node = self._file_node()
        if node is None:
            return
        default = f"./{node.rsplit('/', 1)[-1] or 'node'}.yaml"

        def answered(path: str | None) -> None:
            if path:
                self.write_file(node, path)

        self.app.push_screen(PathScreen(f"Write {node}'s parameters to", default), answered)

    def action_open_file(self) -> None:
        node = self._file_node()
        if node is None:
            return

        def answered(path: str | None) -> None:
            if path:
                self.load_file(node, path)

        self.app.push_screen(PathScreen(f"Load parameters into {node} from", ""), answered)

    @work(group="params-file", exclusive=True, exit_on_error=False)
    async def write_file(self, node: str, path: str) -> None:
        assert self.request is not None
        try:
            dumped = await self.request(ParamsDump(node=node))
        except Exception as exc:
            self.show_result(f"{node}: {_one_line(exc)}", ok=False)
            return
        target = Path(path).expanduser()
        try:
            target.write_text(str(dumped["yaml"]))
        except OSError as exc:
            self.show_result(f"cannot write {path}: {exc.strerror or exc}", ok=False)
            return
        self.show_result(f"wrote {node}'s parameters to {target}", ok=True)

    @work(group="params-file", exclusive=True, exit_on_error=False)
    async def load_file(self, node: str, path: str) -> None:
        assert self.request is not None
        try:
            text = Path(path).expanduser().read_text()
        except (OSError, UnicodeDecodeError) as exc:
            self.show_result(f"cannot read {path}: {getattr(exc, 'strerror', None) or exc}",
                             ok=False)
            return
        try:
            loaded = await self.request(ParamsLoad(node=node, yaml=text))
        except Exception as exc:
            self.show_result(f"{path} into {node}: {_one_line(exc)}", ok=False)
            return
        results = loaded.get("results") or []
        refused = [r for r in results if not r.get("ok")]
        answers = "  ".join(f"{'ok' if r.get('ok') else 'refused'} {r.get('name')}"
                            + (f" ({r['reason']})" if r.get("reason") and not r.get("ok")
                               else "") for r in results)
        self.show_result(f"{path} into {node}: {len(results) - len(refused)} set, "
                         f"{len(refused)} refused: {answers}", ok=not refused)
        self.load_node(node, announce=False)


def _one_line(exc: BaseException) -> str:
    return (str(exc).strip().splitlines() or [type(exc).__name__])[0]
