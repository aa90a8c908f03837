"""The private Textual names tuilaunch relies on (tui/textual_compat.py) are all there,
with the shape relied on: this fails on the Textual upgrade that removes or reshapes one,
naming it, before keys go astray in a running TUI."""

from __future__ import annotations

import inspect

import pytest
from textual import events
from textual.widgets import Input
from textual.widgets._footer import FooterKey

from tuilaunch.tui import textual_compat
from tuilaunch.tui.key_order import keep_escape_before_punctuation
from tuilaunch.tui.textual_compat import INTERNALS, Internal, resolve


@pytest.mark.parametrize("internal", INTERNALS, ids=[i.where for i in INTERNALS])
def test_each_internal_is_there_with_its_shape(internal: Internal):
    try:
        found = resolve(internal)
    except (ImportError, AttributeError) as exc:
        pytest.fail(f"Textual no longer has {internal.where} ({exc}): it was used for "
                    f"{internal.why}")
    if internal.shape.startswith("call("):
        wanted = [p.strip() for p in internal.shape[5:-1].split(",") if p.strip()]
        assert callable(found), f"{internal.where} is no longer callable"
        assert list(inspect.signature(found).parameters) == wanted, \
            f"{internal.where} changed its parameters: used for {internal.why}"
    elif internal.shape == "attribute":
        owner, attribute = found
        instance = {"MessagePump": lambda: owner(), "Message": lambda: events.Key("a", "a"),
                    "DOMNode": lambda: Input(),
                    "FooterKey": lambda: FooterKey("s", "s", "Stop", "stop")}[owner.__name__]()
        assert hasattr(instance, attribute), \
            f"a fresh {owner.__name__} has no {attribute}: used for {internal.why}"
    else:
        assert found is not None


def test_the_attributes_hold_what_the_uses_read():
    pump = Input()
    assert not textual_compat.has_messages(pump)  # a queue with empty()
    assert not textual_compat.is_closing(pump)
    key = events.Key("a", "a")
    textual_compat.send_as_app(key)
    assert key._sender is None
    assert [b.action for b in textual_compat.own_bindings(pump, "home")] == ["home"]
    assert textual_compat.character_to_key("/") == "slash"
    assert textual_compat.unicode_name_of_key("left_square_bracket") == "LEFT SQUARE BRACKET"


def test_every_private_name_used_by_the_tui_is_listed():
    """No underscore name of Textual is reached outside the compatibility module, except
    the private handlers it lists (overridden by name)."""
    import pathlib
    import re

    listed = {i.where.rsplit(".", 1)[-1].rsplit(":", 1)[-1] for i in INTERNALS}
    tui = pathlib.Path(textual_compat.__file__).parent
    for path in tui.rglob("*.py"):
        if path.name == "textual_compat.py":
            continue
        text = path.read_text()
        private = re.search(r"from textual[\w.]*\._\w+ import|import textual\._|"
                            r"from textual[\w.]* import \(?[^)]*?\b_[a-z]\w*", text)
        assert private is None, f"{path.name} reaches {private.group()}: use textual_compat"
        for name in re.findall(r"def (_on_[a-z_]+)\(", text):
            assert name in listed, f"{path.name} overrides Textual's {name}: list it"


async def test_escape_then_slash_in_one_read_stays_two_keys():
    """The wrapped parser method does what key_order relies on, in this Textual."""
    keep_escape_before_punctuation()
    parser = textual_compat.xterm_parser()()
    keys = [e.key for e in parser.feed("\x1b/") if isinstance(e, events.Key)]
    keys += [e.key for e in parser.feed("") if isinstance(e, events.Key)]
    assert keys == ["alt+slash"]
