"""The topics view's data: every topic with types, endpoints, QoS, this launch's processes,
and the publisher/subscriber pairs that cannot talk, said plainly."""

from __future__ import annotations

import json
from typing import Any

from tuilaunch.engine.ros.bridge import RosBridge

from .inspector_helpers import eventually, ros_nodes, run

NS = "/graph_test"
NODES = (
    ["be_pub", "--namespace", NS, "--pub", "scan", "--best-effort", "--rate", "20"],
    ["rel_sub", "--namespace", NS, "--sub", "scan"],
    ["vol_pub", "--namespace", NS, "--pub", "map"],
    ["tl_sub", "--namespace", NS, "--sub", "map", "--transient-local"],
    ["ok_sub", "--namespace", NS, "--sub", "map"],
)
IN_LAUNCH = {f"{NS}/be_pub": "1", f"{NS}/rel_sub": "2", f"{NS}/vol_pub": "3"}


def by_name(graph: dict[str, Any]) -> dict[str, dict[str, Any]]:
    return {t["name"]: t for t in graph["topics"]}


def endpoint_nodes(topic: dict[str, Any] | None, kind: str) -> set[str]:
    return {e["node"] for e in (topic or {}).get(kind, [])}


async def settled(bridge: RosBridge) -> dict[str, Any]:
    """The graph once every test node's endpoint was discovered under its node's name
    (DDS may report an endpoint before the name of the node that owns it)."""
    async def check() -> dict[str, Any] | None:
        graph = await bridge.topics(IN_LAUNCH)
        topics = by_name(graph)
        scan, map_ = topics.get(f"{NS}/scan"), topics.get(f"{NS}/map")
        wanted = [(scan, "publishers", {f"{NS}/be_pub"}),
                  (scan, "subscribers", {f"{NS}/rel_sub"}),
                  (map_, "publishers", {f"{NS}/vol_pub"}),
                  (map_, "subscribers", {f"{NS}/tl_sub", f"{NS}/ok_sub"})]
        if all(endpoint_nodes(t, kind) == nodes for t, kind, nodes in wanted):
            return graph
        return None
    return await eventually(check, 60, "all test endpoints discovered")


def test_topics_list_types_endpoints_qos_and_launch_processes():
    with ros_nodes(*NODES):
        graph = run(settled)
    json.dumps(graph)  # the --json output is this, as is
    scan = by_name(graph)[f"{NS}/scan"]
    assert scan["types"] == ["std_msgs/msg/String"]
    (pub,) = scan["publishers"]
    assert pub["node"] == f"{NS}/be_pub"
    assert pub["in_launch"] is True and pub["process"] == "1"
    assert pub["qos"]["reliability"] == "best_effort"
    assert pub["qos"]["durability"] == "volatile"
    assert {"history", "depth", "deadline", "liveliness"} <= set(pub["qos"])
    map_ = by_name(graph)[f"{NS}/map"]
    outsiders = [s for s in map_["subscribers"] if s["node"] == f"{NS}/ok_sub"]
    assert outsiders == [{"node": f"{NS}/ok_sub", "in_launch": False, "process": None,
                          "qos": outsiders[0]["qos"]}]
    # the inspector's own node is not shown among the endpoints
    assert all("tuilaunch_inspector_test" not in e["node"]
               for t in graph["topics"] for e in (*t["publishers"], *t["subscribers"]))


def test_incompatible_qos_pairs_are_sentences_naming_both_nodes_and_the_policy():
    with ros_nodes(*NODES):
        graph = run(settled)
    topics = by_name(graph)
    (reliability,) = topics[f"{NS}/scan"]["qos_problems"]
    assert f"{NS}/be_pub" in reliability and f"{NS}/rel_sub" in reliability
    assert "reliability" in reliability and "best_effort" in reliability
    (durability,) = topics[f"{NS}/map"]["qos_problems"]  # ok_sub (volatile) can talk
    assert f"{NS}/vol_pub" in durability and f"{NS}/tl_sub" in durability
    assert "durability" in durability and "transient_local" in durability
    assert f"{NS}/ok_sub" not in durability


def test_one_nodes_topics():
    with ros_nodes(*NODES):
        async def scenario(bridge: RosBridge) -> dict[str, Any]:
            await settled(bridge)
            return await bridge.topics(IN_LAUNCH, f"{NS}/tl_sub")
        graph = run(scenario)
    names = [t["name"] for t in graph["topics"]]
    assert f"{NS}/map" in names and f"{NS}/scan" not in names
    assert "/rosout" in names  # every node publishes its log there


def test_deadline_and_liveliness_incompatibilities_as_dds_defines_them():
    from rclpy.duration import Duration
    from rclpy.qos import LivelinessPolicy, QoSProfile

    from tuilaunch.engine.ros.graph.topic_graph import pair_problem

    slow = QoSProfile(depth=10, deadline=Duration(seconds=2))
    fast = QoSProfile(depth=10, deadline=Duration(seconds=1))
    problem = pair_problem("/odom", "/a/pub", slow, "/b/sub", fast)
    assert problem is not None
    assert "deadline" in problem and "/a/pub" in problem and "/b/sub" in problem
    assert pair_problem("/odom", "/a/pub", fast, "/b/sub", slow) is None
    automatic = QoSProfile(depth=10, liveliness=LivelinessPolicy.AUTOMATIC)
    manual = QoSProfile(depth=10, liveliness=LivelinessPolicy.MANUAL_BY_TOPIC)
    problem = pair_problem("/odom", "/a/pub", automatic, "/b/sub", manual)
    assert problem is not None and "liveliness" in problem
    assert pair_problem("/odom", "/a/pub", manual, "/b/sub", automatic) is None
