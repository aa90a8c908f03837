"""The service panel: live services, a request form from the type, call, YAML response."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import yaml
from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.widgets import Button, Input, Label, OptionList, Static
from textual.widgets.option_list import Option

from ...client.inspect.session_graph import GraphCalls
from ...engine.describe.parameter_files import dotted
from ...engine.errors import LaunchError
from ...engine.ros.messages import FieldInfo
from ...engine.ros.ros_errors import MessageError, RosError
from ..key_order import KeyHold, hold_keys
from .fields import Field
from .graph_listing import GraphListing, refill


@dataclass
class CallRecord:
    service: str
    type: str
    request: dict[str, Any]
    outcome: str
    ok: bool


def leaf_fields(fields: list[FieldInfo], prefix: str = "") -> list[tuple[str, FieldInfo]]:
    """Nested messages flattened to dotted paths: one input per leaf."""
    out = []
    for info in fields:
        if info.children:
            out += leaf_fields(info.children, f"{prefix}{info.name}.")
        else:
            out.append((f"{prefix}{info.name}", info))
    return out


def field_text(info: FieldInfo) -> str:
    if isinstance(info.default, str) and not info.is_sequence:
        return info.default
    return yaml.safe_dump(info.default, default_flow_style=True).strip().removesuffix("...")\
        .strip()


def parse_field(info: FieldInfo, text: str) -> Any:
    """A form value in the field's type; strings stay text, booleans are true or false
    (YAML's `yes` is not), and what does not fit names the field."""
    scalar = not info.is_sequence and not info.children
    if info.type.startswith(("string", "wstring")) and scalar:
        return text
    if info.type == "boolean" and scalar:
        lowered = text.strip().lower()
        if lowered not in ("true", "false"):
            raise MessageError(f"field '{info.name}' needs a boolean (true or false), "
                               f"got {text!r}")
        return lowered == "true"
    try:
        return yaml.safe_load(text) if text.strip() else info.default
    except yaml.YAMLError as exc:
        detail = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise MessageError(f"field '{info.name}': {text!r} is not a value ({detail})")\
            from None


def nest(flat: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for path, value in flat.items():
        parts = path.split(".")
        target = out
        for part in parts[:-1]:
            target = target.setdefault(part, {})
        target[parts[-1]] = value
    return out


# services every rclpy/rclcpp node offers: listed only when the filter asks for them
_STANDARD = ("/describe_parameters", "/get_parameter_types", "/get_parameters",
             "/list_parameters", "/set_parameters", "/set_parameters_atomically",
             "/get_type_description")


class ServicesPanel(GraphListing, Horizontal):
    DEFAULT_CSS = """
    ServicesPanel #svc-left { width: 45%; min-width: 36; max-width: 64;
                              border-right: tall $panel; }
    ServicesPanel #svc-list { height: 2fr; border-title-align: left; }
    ServicesPanel #svc-history { height: 1fr; border-top: solid $panel; }
    ServicesPanel #svc-right { width: 1fr; padding: 0 1; }
    ServicesPanel #svc-title { height: auto; text-style: bold; }
    ServicesPanel #svc-form { height: auto; max-height: 12; }
    ServicesPanel .svc-field { height: 3; }
    ServicesPanel .svc-field Label { width: 18; padding-top: 1; }
    ServicesPanel .svc-field Input { width: 1fr; }
    ServicesPanel #svc-call-row { height: 3; }
    ServicesPanel #svc-response { height: 1fr; }
    ServicesPanel #svc-response.error { color: $error; }
    """

    listing = "services"

    def __init__(self, graph: Callable[[], GraphCalls], timeout: float = 5.0,
                 **kwargs: object) -> None:
        """`graph()`: where the services are listed, described and called (the session's)."""
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.graph = graph
        self.timeout = timeout
        self.services: list[tuple[str, list[str]]] = []
        self.selected: tuple[str, str] | None = None
        self.form_of: tuple[str, str] | None = None  # the service whose form is shown
        self.fields: list[tuple[str, FieldInfo]] = []
        self.history: list[CallRecord] = []
        self._submit_waits = False
        """Enter was pressed in the filter while nothing matched: discovery may not have
        seen the service yet. The next listing with a match picks it; typing cancels."""

    def compose(self) -> ComposeResult:
        with Vertical(id="svc-left"):
            yield Field(placeholder="filter services", id="svc-filter")
            yield OptionList(id="svc-list")
            yield OptionList(id="svc-history")
        with Vertical(id="svc-right"):
            yield Static("Pick a service on the left.", id="svc-title")
            yield VerticalScroll(id="svc-form")
            with Horizontal(id="svc-call-row"):
                yield Button("Call", id="svc-call", variant="primary", disabled=True)
                yield Button("Refresh list", id="svc-refresh")
            yield Static("", id="svc-response")

    def on_mount(self) -> None:
        self.query_one("#svc-history", OptionList).border_title = "history"
        self.query_one("#svc-list", OptionList).border_title = self.title(0, "", "service")

    def show_listing(self, listing: list[tuple[str, list[str]]], reload: bool) -> None:
        if listing != self.services or not self.query_one("#svc-list", OptionList).option_count:
            self.services = listing
            self._fill_list()
        if self._submit_waits and self.query_one("#svc-list", OptionList).option_count:
            # Enter came while the graph was still being discovered: now it has a match
            self._submit_waits = False
            self._filter_submitted()

    @on(Input.Changed, "#svc-filter")
    def _typed(self) -> None:
        self._submit_waits = False  # a new term: the Enter was for the old one
        self._fill_list()

    def _fill_list(self) -> None:
        term = self.query_one("#svc-filter", Input).value.lower()
        listing = self.query_one("#svc-list", OptionList)
        shown = [name for name, types in self.services
                 if (term in name.lower() or any(term in t.lower() for t in types))
                 and (term or not name.endswith(_STANDARD))]
        hidden = "" if term else ", node parameter services hidden: type to search all"
        if not refill(listing, shown, self.title(len(shown), term, "service", hidden)) \
                and listing.option_count:
            listing.highlighted = 0

    @on(Input.Submitted, "#svc-filter")
    def _filter_submitted(self) -> None:
        """Enter in the filter picks the first match: type a few letters, enter, call."""
        listing = self.query_one("#svc-list", OptionList)
        if listing.option_count:
            self._open_form(str(listing.get_option_at_index(listing.highlighted or 0).id))
        else:
            # nothing matches yet (`3/ena` Enter in one read, while discovery still runs,
            # or the graph has other services but not yet this one): the Enter picks the
            # first match once a listing has it, rather than being lost
            self._submit_waits = True

    def _open_form(self, name: str) -> None:
        """Picks the service and moves on to its request's first field. The keys typed
        meanwhile (its value, typed in the same read as Enter: `/ena` Enter `true` Enter)
        wait for that field, where they would otherwise reach the list or the filter."""
        hold = hold_keys(self.app)
        self.select_service(name, (dict(self.services).get(name) or ["?"])[0],
                            then=lambda: self.call_after_refresh(self._focus_form, hold))

    def _focus_form(self, hold: KeyHold) -> None:
        """Once the form is mounted: the first field, or Call for an empty request."""
        inputs = self.query("#svc-form Input")
        (inputs.first() if inputs else self.query_one("#svc-call")).focus()
        hold.release()

    @on(Button.Pressed, "#svc-refresh")
    def _refresh(self) -> None:
        self.refresh_listing()

    @on(OptionList.OptionSelected, "#svc-list")
    def _picked(self, event: OptionList.OptionSelected) -> None:
        self._open_form(str(event.option.id))  # Enter on a row: on to its request

    def select_service(self, name: str, type_name: str,
                       values: dict[str, str] | None = None, then: Callable[[], Any] | None = None,
                       ) -> None:
        """Shows the service's request form, once its fields are known (asked of the
        session: the message package need not be installed here); `then` runs after,
        whether the form came or not (refused, or another service picked meanwhile)."""
        self.selected = (name, type_name)
        self.query_one("#svc-call", Button).disabled = True  # until its form is there
        self.show_form(name, type_name, values, then)

    @work(group="services-form", exclusive=True, exit_on_error=False)
    async def show_form(self, name: str, type_name: str, values: dict[str, str] | None,
                        then: Callable[[], Any] | None) -> None:
        try:
            await self._show_form(name, type_name, values)
        finally:
            if then is not None:
                then()

    async def _show_form(self, name: str, type_name: str,
                         values: dict[str, str] | None) -> None:
        title = self.query_one("#svc-title", Static)
        form = self.query_one("#svc-form", VerticalScroll)
        try:
            fields = await self.graph().service_fields(type_name)
        except Exception as exc:  # not installed there, the session gone: said, not raised
            self.selected = None
            await form.remove_children()
            title.update(Text(f"{name}  {type_name}"))
            self.show_response(str(exc), ok=False)
            return
        if self.selected != (name, type_name):
            return  # another service was picked meanwhile
        await form.remove_children()
        self.fields = leaf_fields(fields)
        self.form_of = (name, type_name)
        title.update(Text(f"{name}  {type_name}" + ("" if self.fields else "  (empty request)")))
        for path, info in self.fields:
            text = (values or {}).get(path, field_text(info))
            await form.mount(Horizontal(Label(path),
                                        Field(text, id=f"field-{path.replace('.', '-')}",
                                              tooltip=info.type), classes="svc-field"))
        self.query_one("#svc-call", Button).disabled = False

    def request(self) -> dict[str, Any]:
        flat = {}
        for path, info in self.fields:
            text = self.query_one(f"#field-{path.replace('.', '-')}", Input).value
            flat[path] = parse_field(info, text)
        return nest(flat)

    @on(Button.Pressed, "#svc-call")
    @on(Input.Submitted, "#svc-form Input")
    def _call(self) -> None:
        self.call_selected()

    @work(group="services-call", exclusive=True, exit_on_error=False)
    async def call_selected(self) -> None:
        if self.selected is None or self.form_of != self.selected:
            return  # its form is not there yet: the fields on screen are another's
        name, type_name = self.selected
        try:
            request = self.request()
            self.show_response(f"calling {name} ...", ok=True)
            _, response = await self.graph().call_service(
                name, request, timeout=self.timeout, service_type=type_name)
        except (MessageError, LaunchError, RosError) as exc:  # a session's refusal is one
            self._record(CallRecord(name, type_name, {}, str(exc), False))
            return
        except Exception as exc:  # anything else is shown, never raised into the app
            self._record(CallRecord(name, type_name, {}, f"{type(exc).__name__}: {exc}", False))
            return
        text = yaml.safe_dump(response, sort_keys=False, default_flow_style=False).strip()
        self._record(CallRecord(name, type_name, request, text, True))

    def _record(self, record: CallRecord) -> None:
        self.history.append(record)
        self.show_response(record.outcome, record.ok)
        mark = "ok" if record.ok else "error"
        self.query_one("#svc-history", OptionList).add_option(
            Option(f"{len(self.history)}. {record.service} {mark}", id=str(len(self.history))))

    @on(OptionList.OptionSelected, "#svc-history")
    def _recall(self, event: OptionList.OptionSelected) -> None:
        record = self.history[int(str(event.option.id)) - 1]
        flat = {path: yaml.safe_dump(value, default_flow_style=True).strip().removesuffix(
            "...").strip() if not isinstance(value, str) else value
            for path, value in dotted(record.request).items()}
        self.select_service(record.service, record.type, flat)
        self.show_response(record.outcome, record.ok)

    def show_response(self, text: str, ok: bool) -> None:
        response = self.query_one("#svc-response", Static)
        response.update(Text(text))
        response.set_class(not ok, "error")

    report = show_response

