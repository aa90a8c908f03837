"""The session's requests as classes: every request and its reply through the one codec
(vocabulary/request.py), the wire as the protocol's earlier clients wrote it, and a message
no request fits refused in one line."""

from __future__ import annotations

import dataclasses
import json
import typing
from typing import Any

import pytest

from tuilaunch.client.read_only import ReadOnlyError, check_request
from tuilaunch.engine.run.vocabulary.request import (
    REQUESTS,
    Request,
    UnknownRequest,
    from_message,
    to_message,
)
from tuilaunch.engine.run.vocabulary.requests import (
    Apply,
    EchoStart,
    Find,
    Kill,
    ReadLog,
    Restart,
    Status,
    Subscribe,
    TakeKeys,
    Topics,
    Transition,
    WatchResources,
)

SAMPLES: dict[Any, Any] = {str: "talker-1", int: 7, float: 2.5, Any: {"tag": 1}}


def sample(hint: Any, default: Any) -> Any:
    """A value of the field's type that is not its default (so the wire carries it)."""
    args = [a for a in typing.get_args(hint) if a is not type(None)]
    if type(None) in typing.get_args(hint) and args:
        hint = args[0]
    origin = typing.get_origin(hint)
    if hint is bool:
        return not default
    if origin is list:
        return ["/a", "/b"]
    if origin is dict:
        return {"robot": "r1"}
    return SAMPLES[hint]


def filled(cls: type[Request[Any]]) -> Request[Any]:
    hints = typing.get_type_hints(cls)
    return cls(**{f.name: sample(hints[f.name], f.default)
                  for f in dataclasses.fields(cls)})  # type: ignore[arg-type]


def test_every_request_has_its_own_op_and_a_dataclass():
    assert len(REQUESTS) >= 48
    for op, cls in REQUESTS.items():
        assert cls.op == op
        assert dataclasses.is_dataclass(cls), cls


@pytest.mark.parametrize("op", sorted(REQUESTS))
def test_every_request_round_trips_through_json(op):
    """Each field set (not at its default) goes over the wire and comes back the same."""
    asked = filled(REQUESTS[op])
    line = json.dumps(to_message(asked, 12))
    message = json.loads(line)
    assert message["id"] == 12 and message["op"] == op
    assert from_message({**message, "client": 99}) == asked  # the server's keys are not its


@pytest.mark.parametrize("op", sorted(REQUESTS))
def test_a_request_at_its_defaults_is_its_op_and_its_required_fields(op):
    cls = REQUESTS[op]
    hints = typing.get_type_hints(cls)
    fields = dataclasses.fields(cls)  # type: ignore[arg-type]
    required = {f.name: sample(hints[f.name], None) for f in fields
                if f.default is dataclasses.MISSING and
                f.default_factory is dataclasses.MISSING}
    asked = cls(**required)
    assert to_message(asked) == {"op": op, **required}
    assert from_message(to_message(asked)) == asked


def test_the_wire_is_the_untyped_clients_wire():
    """What the earlier clients wrote, field for field (the protocol version is unchanged)."""
    assert to_message(Status(resources=False), 3) == {"id": 3, "op": "status",
                                                      "resources": False}
    assert to_message(Status()) == {"op": "status"}
    assert to_message(Restart("talker-1", log_level="debug")) == {
        "op": "restart", "process": "talker-1", "log_level": "debug"}
    assert to_message(Restart("talker-1", terminal=True)) == {
        "op": "restart", "process": "talker-1", "terminal": True}
    assert to_message(ReadLog("launch", limit=0)) == {"op": "read_log", "process": "launch",
                                                      "limit": 0}
    assert to_message(EchoStart("/chatter", max_per_s=0)) == {
        "op": "echo", "topic": "/chatter", "max_per_s": 0}
    assert to_message(Subscribe(max_lines=1, kinds=["hz"])) == {
        "op": "subscribe", "max_lines": 1, "kinds": ["hz"]}
    assert to_message(Kill(), 1) == {"id": 1, "op": "kill"}


def test_a_message_from_an_older_client_reads_as_the_server_read_it():
    assert from_message({"op": "status"}) == Status(resources=True)
    assert from_message({"op": "read_log", "process": "x", "start": "40", "end": None}) == \
        ReadLog("x", start=40)
    assert from_message({"op": "topics", "node": None}) == Topics()
    assert from_message({"op": "typing", "process": "p", "on": 1}) == TakeKeys("p", on=True)
    assert from_message({"op": "watch_resources", "processes": None}) == WatchResources()


@pytest.mark.parametrize(("message", "said"), [
    ({"op": "reboot"}, "unknown request 'reboot'"),
    ({"id": 3}, "unknown request None"),
    ({"op": 7}, "unknown request 7"),
    ({"op": "start"}, "request start needs process"),
    ({"op": "start", "process": None}, "request start needs process"),
    ({"op": "read_log", "process": "x", "start": "the top"},
     "request read_log: start must be int, not 'the top'"),
    ({"op": "apply", "arguments": ["robot:=r1"]},
     "request apply: arguments must be an object, not ['robot:=r1']"),
    ({"op": "watch_rates", "topics": "/chatter"},
     "request watch_rates: topics must be a list, not '/chatter'"),
])
def test_a_message_no_request_fits_is_one_clear_line(message, said):
    with pytest.raises(UnknownRequest) as caught:
        from_message(message)
    assert str(caught.value) == said
    assert "\n" not in str(caught.value)


def test_replies_are_read_as_their_request_says():
    assert Find("talker").reply("talker-1") == "talker-1"
    assert Transition("lc-1", "configure").reply({"process": "lc-1", "done": True}) is True
    assert Transition("lc-1", "configure").reply({"process": "lc-1", "done": False}) is False
    assert Apply({"robot": "r2"}).reply({"stop": ["a"], "start": ["b"]}) == \
        {"stop": ["a"], "start": ["b"]}


def test_a_read_only_client_refuses_what_changes_and_asks_what_reads():
    changing = {op for op, cls in REQUESTS.items() if cls.changes is not None}
    assert changing == {"start", "stop", "restart", "shutdown", "kill", "apply",
                        "run_action", "transition", "typing", "input", "log_level",
                        "params_load", "call_service", "params_set", "plan_shown"}
    for op in sorted(changing):
        with pytest.raises(ReadOnlyError, match=r"^read-only view: .* is refused$"):
            check_request(filled(REQUESTS[op]))
    for op in sorted(set(REQUESTS) - changing):
        check_request(filled(REQUESTS[op]))  # only reads: goes through


def test_two_requests_cannot_share_an_op():
    with pytest.raises(TypeError, match="two requests with op 'status'"):
        @dataclasses.dataclass(frozen=True)
        class Other(Request[Any], op="status"):
            pass
