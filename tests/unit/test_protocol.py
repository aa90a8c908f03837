"""The session protocol's messages alone (engine/run/session/protocol.py): a greeting's
version checked, events through their wire form and back. The same with a real server,
the command line and ssh: tests/integration/test_protocol_version.py."""

from __future__ import annotations

from dataclasses import replace

import pytest

from tuilaunch import __version__
from tuilaunch.engine.run.events import (
    EVENT_TYPES,
    Event,
    ExitCause,
    Output,
    ProcessExited,
    Respawning,
    Started,
    Stopping,
    event_of,
)
from tuilaunch.engine.run.session.protocol import (
    PROTOCOL_VERSION,
    Stamps,
    VersionMismatch,
    check_hello,
    decode,
    encode,
    event_from_dict,
    event_to_dict,
)
from tuilaunch.engine.run.session.session_dir import SessionError


def hello(**info: object) -> dict:
    return decode(encode({"type": "hello", "info": {"name": "demo", **info}}))


def test_a_greeting_of_this_version_gives_its_info():
    assert check_hello(hello(protocol=PROTOCOL_VERSION, tuilaunch=__version__), "demo")[
        "name"] == "demo"


def test_another_version_is_one_line_naming_both():
    with pytest.raises(VersionMismatch) as raised:
        check_hello(hello(protocol=PROTOCOL_VERSION + 1, tuilaunch="9.9.9"), "robot1:demo")
    assert str(raised.value) == (
        f"session robot1:demo speaks protocol {PROTOCOL_VERSION + 1} (tuilaunch 9.9.9), this "
        f"tuilaunch speaks {PROTOCOL_VERSION} ({__version__}): use the same tuilaunch on "
        "both sides")
    assert "\n" not in str(raised.value)


def test_a_greeting_without_a_version_is_protocol_1():
    with pytest.raises(VersionMismatch, match="speaks protocol 1 \\(a tuilaunch from before"):
        check_hello(hello(), "demo")


def test_something_else_than_a_greeting_is_refused():
    with pytest.raises(SessionError, match="session demo did not greet"):
        check_hello({"type": "reply"}, "demo")


@pytest.mark.parametrize("event", [
    Started("talker-1", pid=42),
    Output("talker-1", lines=["a", "b"], stream="stderr"),
    Stopping("talker-1", pid=42),
    Respawning("talker-1", reason="try 1 in 2 s", data={"try": 1, "delay": 2.0}),
    Event("state", "talker-1", data={"state": "active"}),  # a kind no class knows
])
def test_events_come_back_as_they_went(event: Event):
    back = event_from_dict(decode(encode(event_to_dict(event))))
    assert type(back) is type(event)
    assert back == replace(event, time=round(event.time, 3))


@pytest.mark.parametrize("kind", sorted(EVENT_TYPES))
def test_every_kind_comes_back_as_its_own_class(kind: str):
    made = event_of(kind, process="p", reason="why", data={"requested": True})
    back = event_from_dict(decode(encode(event_to_dict(made))))
    assert type(back) is EVENT_TYPES[kind] and back.kind == kind
    assert back.process == "p"
    # a dropped count's sentence is the client's to write: the wire leaves it out
    assert back.reason == (None if kind == "dropped" else "why")


def test_an_event_class_is_made_without_its_kind():
    """The first argument of every event class is its process, never its kind."""
    assert Stopping("a").process == "a" and Stopping("a").kind == "stopping"
    with pytest.raises(TypeError):
        Started(kind="output")  # type: ignore[call-arg]


def test_stamps_go_apart_and_come_back():
    data = {"lines": ["[INFO] [12.345] [n]: a", "plain", "[WARN] [12.400] [n]: b"]}
    sender, receiver = Stamps(), Stamps()
    sent = dict(data)
    assert sender.pack(sent) == [12345, None, 12400]
    assert sent["lines"] == ["[INFO] [n]: a", "plain", "[WARN] [n]: b"]
    receiver.unpack(sent)
    assert sent["lines"] == data["lines"]


@pytest.mark.parametrize(("code", "data", "cause"), [
    (0, {"requested": False, "typed": False}, ExitCause.CLEAN),
    (-11, {"requested": False, "typed": False, "signal": "SIGSEGV"}, ExitCause.CRASHED),
    (3, {"requested": False, "typed": False}, ExitCause.CRASHED),
    (-2, {"requested": True, "typed": False}, ExitCause.ASKED),
    (0, {"requested": True, "typed": False}, ExitCause.ASKED),
    (-2, {"requested": True, "typed": True}, ExitCause.TYPED),
])
def test_an_end_keeps_its_cause_through_the_wire(code, data, cause):
    """The cause is decided where the process ended; a client reads the same one."""
    sent = ProcessExited(process="talker-1", pid=42, code=code, reason="r", data=data,
                         cause=ExitCause.of(code, data["requested"], data["typed"]))
    assert sent.cause is cause
    back = event_from_dict(decode(encode(event_to_dict(sent))))
    assert isinstance(back, ProcessExited) and back.kind == "exited"
    assert back.cause is cause
    assert back.crashed == (cause is ExitCause.CRASHED)
    assert back.asked == (cause in (ExitCause.ASKED, ExitCause.TYPED))
