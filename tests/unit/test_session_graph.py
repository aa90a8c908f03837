"""A service's request form crosses the session as dicts (engine/ros/graph_requests.py)
and comes back as the FieldInfo the Services tab builds its form from
(client/session_graph.py), nested messages too."""

from __future__ import annotations

import dataclasses

from tuilaunch.client.inspect.session_graph import field_info
from tuilaunch.engine.ros.messages import describe_fields, import_type
from tuilaunch.engine.run.session.protocol import decode, encode


def test_a_request_form_comes_back_whole_through_the_wire():
    for type_name in ("std_srvs/srv/SetBool", "rcl_interfaces/srv/SetParameters",
                      "lifecycle_msgs/srv/ChangeState"):
        fields = describe_fields(import_type(type_name).Request)
        sent = decode(encode({"fields": [dataclasses.asdict(f) for f in fields]}))
        assert [field_info(f) for f in sent["fields"]] == fields


def test_a_nested_message_keeps_its_children():
    """lifecycle_msgs ChangeState's request is a Transition message: its fields come along."""
    fields = describe_fields(import_type("lifecycle_msgs/srv/ChangeState").Request)
    back = [field_info(f) for f in decode(encode(
        {"fields": [dataclasses.asdict(f) for f in fields]}))["fields"]]
    (transition,) = back
    assert [child.name for child in transition.children] == ["id", "label"]
