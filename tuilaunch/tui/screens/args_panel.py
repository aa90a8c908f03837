"""The argument form: an editor per argument type; edits are previewed before applying."""

from __future__ import annotations

import os
import re

from rich.text import Text
from textual import on
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical, VerticalScroll
from textual.message import Message
from textual.widget import Widget
from textual.widgets import Button, Checkbox, Input, Label, Select, Static

from ...engine.describe.substitutions import text_to_bool
from ...engine.plan.arguments import check_values as check_values
from ...engine.plan.arguments import type_notes as type_notes
from ...engine.plan.model import ArgumentInfo, Plan
from .fields import Field, Toggle

# ROS 2 name rules (rcl's validate_namespace / validate_node_name)
_NAMESPACE = re.compile(r"^(/|(/[A-Za-z_][A-Za-z0-9_]*)+)$")
_NODE_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def check_plan(plan: Plan) -> str | None:
    """What in a resolved plan could not start: a bad namespace or node name, an error."""
    for proc in plan.processes:
        if not proc.enabled:
            continue
        if proc.error:
            return f"{proc.id}: {proc.error}"
        namespace = proc.namespace
        if proc.kind == "node" and namespace and not _NAMESPACE.match(namespace):
            return f"{proc.id}: namespace {namespace!r} is not a valid ROS namespace"
        if proc.kind == "node" and proc.name and not _NODE_NAME.match(proc.name):
            return f"{proc.id}: node name {proc.name!r} is not a valid ROS name"
    return None


class FormButton(Button):
    """Apply and Defaults: a bar of two buttons above the values. `tab` goes from either
    straight to the first value (the values are what one edits; Defaults is one `right`
    away), `left`/`right` move along the bar, and a space presses nothing (only Enter
    does: a space typed for a value must not reset the whole form)."""

    BINDINGS = [Binding("tab", "to_values", "Values", show=False),
                Binding("left", "along(-1)", show=False),
                Binding("right", "along(1)", show=False),
                Binding("space", "nothing", show=False)]

    def action_to_values(self) -> None:
        editors = self.screen.query(".arg-editor")
        if editors:
            self.screen.set_focus(editors.first())
        else:
            self.screen.focus_next()

    def action_along(self, step: int) -> None:
        """To the next button along the bar; at its end the focus stays (no wrap: `right`
        pressed once too often on Defaults must not land on Apply, where Enter relaunches)."""
        buttons = list(self.parent.query(FormButton)) if self.parent else [self]
        at = max(0, min(len(buttons) - 1, buttons.index(self) + step))
        self.screen.set_focus(buttons[at])

    def action_nothing(self) -> None:
        pass


def bool_text(arg: ArgumentInfo, state: bool) -> str:
    """A boolean argument's value as the box gives it, never mixing spellings: the running
    value when the box shows its state; a value given on the command line spells the other
    state alike (`listener:=false` checked gives `true`, not the default's `True`); else the
    default's own text for its state, and `true`/`false` as ros2 launch users write them."""
    given = arg.value if arg.value and text_to_bool(arg.value) is not None else None
    if given is not None and text_to_bool(given) == state:
        return given
    default = (arg.default or "").strip()
    if text_to_bool(default) == state and (given is None or given == arg.default):
        return default
    text = "true" if state else "false"
    if given is not None and given != arg.default:
        if given.isdigit():
            return "1" if state else "0"
        if given.isupper():
            return text.upper()
        return text.capitalize() if given[:1].isupper() else text
    return text


def _shown(arg: ArgumentInfo) -> str:
    """The value an argument's editor is drawn with: the running one, else the default."""
    return arg.value if arg.value is not None else (arg.default or "")


def _editors_of(arguments: list[ArgumentInfo]) -> list[tuple[object, ...]]:
    """What decides each argument's editor and its lines, apart from the value."""
    return [(a.name, a.default, a.description, a.type, tuple(a.choices or ()), a.file,
             tuple(a.elsewhere or ()),
             # a value outside the choices is an option of its own
             bool(a.choices) and _shown(a) not in (a.choices or ()) and _shown(a),
             a.type == "bool" and text_to_bool(_shown(a)) is not None) for a in arguments]


class ArgsPanel(Vertical):
    """The Apply and Defaults bar above the values; `shift+tab` from the first value goes
    back to Apply, where the tab starts (not to Defaults, which resets the form)."""

    BINDINGS = [Binding("shift+tab", "back_to_apply", show=False)]
    DEFAULT_CSS = """
    ArgsPanel #args-preview { height: auto; max-height: 4; padding: 0 1; background: $boost; }
    ArgsPanel #args-preview.error { color: $error; }
    ArgsPanel #args-actions { height: 1; }
    ArgsPanel .arg-row { height: auto; padding: 0 1; }
    ArgsPanel .arg-line { height: 1; }
    ArgsPanel .arg-name { width: 18; }
    ArgsPanel .arg-row.changed .arg-name { text-style: bold reverse; }
    ArgsPanel .arg-editor { width: 1fr; }
    ArgsPanel Checkbox.arg-editor { width: auto; }
    ArgsPanel .arg-help { color: $text-muted; padding-left: 18; }
    """

    class Edited(Message):
        """The form's values changed: name -> text, for every argument."""

        def __init__(self, values: dict[str, str]) -> None:
            super().__init__()
            self.values = values

    class ApplyRequested(Message):
        pass

    def __init__(self, arguments: list[ArgumentInfo], top_file: str, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.arguments = arguments
        self.top_file = top_file

    def compose(self) -> ComposeResult:
        yield Static("Edit a value to preview which nodes start or stop; F5 applies.",
                     id="args-preview")
        with Horizontal(id="args-actions"):
            yield FormButton("Apply (F5)", id="apply", variant="primary", compact=True)
            yield FormButton("Defaults", id="defaults", compact=True)
        # not a tab stop of its own: tab goes from the buttons straight to the values
        with VerticalScroll(id="args-form", can_focus=False):
            for arg in self.arguments:
                with Vertical(classes="arg-row", id=f"row-{arg.name}"):
                    with Horizontal(classes="arg-line"):
                        yield Label(arg.name, classes="arg-name")
                        yield self._editor(arg)
                    yield Static(Text(self._help(arg)), classes="arg-help")

    def _help(self, arg: ArgumentInfo) -> str:
        text = arg.description or "(no description)"
        text += f"  [default {arg.default!r}, {arg.type}]"
        if os.path.abspath(arg.file) != os.path.abspath(self.top_file):
            text += f"  from {os.path.basename(arg.file)}"
        if arg.elsewhere:
            text += f"  (also {', '.join(arg.elsewhere)})"
        return text

    def _editor(self, arg: ArgumentInfo) -> Widget:
        value = _shown(arg)
        name = f"arg-{arg.name}"
        if arg.choices:
            options = [(c, c) for c in arg.choices]
            if value not in arg.choices:
                options.append((value, value))
            return Select(options, value=value, allow_blank=False, id=name,
                          classes="arg-editor", compact=True)
        if arg.type == "bool" and text_to_bool(value) is not None:
            state = bool(text_to_bool(value))
            return Toggle(bool_text(arg, state), value=state, id=name,
                          classes="arg-editor", compact=True)
        # typed as text and checked as a whole by the preview: Input's number types drop
        # a refused character silently (1.5 in an int field became 15)
        return Field(value, id=name, classes="arg-editor", compact=True)

    def drawn_values(self) -> dict[str, str]:
        """What `values` gives while nothing is typed: the form as drawn for its arguments
        (a Select says Changed as it mounts, which is not an edit)."""
        out = {}
        for arg in self.arguments:
            value = _shown(arg)
            if not arg.choices and arg.type == "bool" and text_to_bool(value) is not None:
                value = bool_text(arg, bool(text_to_bool(value)))
            out[arg.name] = value
        return out

    def show(self, arguments: list[ArgumentInfo]) -> None:
        """These arguments' values in the form. The same editors are kept and given the
        new values (a relaunch by another client), saying no edit; only other editors (the
        edited file declares other arguments) draw the form anew: removing a Select that
        is still mounting is what Textual raises on."""
        if _editors_of(arguments) != _editors_of(self.arguments):
            self.arguments = arguments
            self.refresh(recompose=True)
            return
        self.arguments = arguments
        wanted = self.drawn_values()
        if self.values() == wanted:
            return
        with self.prevent(Input.Changed, Checkbox.Changed, Select.Changed):
            for arg in arguments:
                editor = self.query_one(f"#arg-{arg.name}")
                value = wanted[arg.name]
                if isinstance(editor, Checkbox):
                    editor.value = bool(text_to_bool(value))
                    editor.label = value
                elif isinstance(editor, Select):
                    editor.value = value
                elif isinstance(editor, Input):
                    editor.value = value
        self.mark_changes()

    def values(self) -> dict[str, str]:
        out = {}
        for arg in self.arguments:
            editor = self.query_one(f"#arg-{arg.name}")
            if isinstance(editor, Checkbox):
                out[arg.name] = bool_text(arg, editor.value)
            elif isinstance(editor, Select):
                out[arg.name] = str(editor.value)
            elif isinstance(editor, Input):
                out[arg.name] = editor.value
        return out

    def mark_changes(self) -> None:
        values = self.values()
        for arg in self.arguments:
            row = self.query_one(f"#row-{arg.name}")
            row.set_class(values[arg.name] != (arg.default or ""), "changed")

    def set_preview_text(self, text: str, error: bool) -> None:
        preview = self.query_one("#args-preview", Static)
        preview.update(Text(text))
        preview.set_class(error, "error")

    def _edited(self) -> None:
        self.mark_changes()
        self.post_message(self.Edited(self.values()))

    @on(Input.Changed)
    @on(Checkbox.Changed)
    @on(Select.Changed)
    def _changed(self, event: Input.Changed | Checkbox.Changed | Select.Changed) -> None:
        if isinstance(event, Checkbox.Changed):
            arg = next((a for a in self.arguments if f"arg-{a.name}" == event.checkbox.id),
                       None)
            # the value it gives, as it will be applied and shown (`listener:=false`)
            event.checkbox.label = bool_text(arg, event.value) if arg else \
                ("true" if event.value else "false")
        if self.is_mounted:
            self._edited()

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        if action == "back_to_apply":  # elsewhere shift+tab goes back as anywhere
            editors = self.query(".arg-editor")
            return bool(editors) and self.screen.focused is editors.first()
        return True

    def action_back_to_apply(self) -> None:
        self.screen.set_focus(self.query_one("#apply", FormButton))

    @on(Button.Pressed, "#apply")
    def _apply(self) -> None:
        self.post_message(self.ApplyRequested())

    @on(Button.Pressed, "#defaults")
    def _defaults(self) -> None:
        for arg in self.arguments:
            editor = self.query_one(f"#arg-{arg.name}")
            default = arg.default or ""
            if isinstance(editor, Checkbox):
                editor.value = bool(text_to_bool(default))
            elif isinstance(editor, Select):
                editor.value = default
            elif isinstance(editor, Input):
                editor.value = default
        self._edited()
