"""The topic graph as the inspector shows it: who publishes and subscribes what, with which
QoS, which of them belong to this launch, and which pairs cannot talk and why.

Reads an rclpy node's discovered graph (call from any thread: the graph queries do not
need the executor). The output is plain dicts, the JSON of `tuilaunch topics --json`.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

_INFINITE_NS = 2**62  # rmw reports "infinite" as 0 or as the largest int64


def full_node_name(name: str, namespace: str) -> str:
    return namespace.rstrip("/") + "/" + name


def topic_of(topic: str) -> str:
    """The topic a request names, absolute as the graph names it."""
    if not topic:
        raise ValueError("a topic name is needed")
    return topic if topic.startswith("/") else "/" + topic


def policy_name(value: Any) -> str:
    """`ReliabilityPolicy.BEST_EFFORT` as `best_effort`, as `ros2 topic info -v` words it."""
    return str(getattr(value, "name", value)).lower()


def duration_text(duration: Any) -> str:
    nanoseconds = int(getattr(duration, "nanoseconds", 0))
    if nanoseconds <= 0 or nanoseconds >= _INFINITE_NS:
        return "infinite"
    return f"{nanoseconds / 1e9:g} s"


def qos_dict(profile: Any) -> dict[str, Any]:
    """An endpoint's QoS as discovered. DDS discovery does not carry history and depth, so
    other processes' endpoints say history "unknown" and depth None (`ros2 topic info -v`
    says UNKNOWN too)."""
    history = policy_name(profile.history)
    return {
        "reliability": policy_name(profile.reliability),
        "durability": policy_name(profile.durability),
        "history": history,
        "depth": None if history == "unknown" else int(profile.depth),
        "deadline": duration_text(profile.deadline),
        "liveliness": policy_name(profile.liveliness),
        "liveliness_lease_duration": duration_text(profile.liveliness_lease_duration),
    }


def _finite_ns(duration: Any) -> int | None:
    nanoseconds = int(getattr(duration, "nanoseconds", 0))
    return None if nanoseconds <= 0 or nanoseconds >= _INFINITE_NS else nanoseconds


def pair_problem(topic: str, publisher: str, pub_qos: Any, subscriber: str,
                 sub_qos: Any) -> str | None:
    """A sentence when this publisher and subscriber cannot talk (DDS's request/offered
    rules, as rmw checks them), naming both nodes and the policy; None when they can."""
    from rclpy.qos import QoSCompatibility, qos_check_compatible

    compatibility, reason = qos_check_compatible(pub_qos, sub_qos)
    if compatibility != QoSCompatibility.ERROR:
        return None
    who = f"on {topic}, publisher {publisher} and subscriber {subscriber} cannot talk"
    pub_r, sub_r = policy_name(pub_qos.reliability), policy_name(sub_qos.reliability)
    if pub_r == "best_effort" and sub_r == "reliable":
        return (f"{who}: reliability: the publisher is best_effort and the subscriber asks for"
                f" reliable (make the subscriber best_effort or the publisher reliable)")
    pub_d, sub_d = policy_name(pub_qos.durability), policy_name(sub_qos.durability)
    if pub_d == "volatile" and sub_d == "transient_local":
        return (f"{who}: durability: the publisher is volatile and the subscriber asks for"
                f" transient_local (make the subscriber volatile or the publisher"
                f" transient_local)")
    pub_deadline, sub_deadline = _finite_ns(pub_qos.deadline), _finite_ns(sub_qos.deadline)
    if sub_deadline is not None and (pub_deadline is None or pub_deadline > sub_deadline):
        return (f"{who}: deadline: the publisher offers {duration_text(pub_qos.deadline)},"
                f" longer than the subscriber's {duration_text(sub_qos.deadline)}")
    pub_l, sub_l = policy_name(pub_qos.liveliness), policy_name(sub_qos.liveliness)
    if pub_l == "automatic" and sub_l == "manual_by_topic":
        return (f"{who}: liveliness: the publisher is automatic and the subscriber asks for"
                f" manual_by_topic")
    pub_lease = _finite_ns(pub_qos.liveliness_lease_duration)
    sub_lease = _finite_ns(sub_qos.liveliness_lease_duration)
    if sub_lease is not None and (pub_lease is None or pub_lease > sub_lease):
        return (f"{who}: liveliness lease duration: the publisher offers"
                f" {duration_text(pub_qos.liveliness_lease_duration)}, longer than the"
                f" subscriber's {duration_text(sub_qos.liveliness_lease_duration)}")
    return f"{who}: {str(reason).strip().rstrip(';')}"


def _endpoints(infos: list[Any], processes: Mapping[str, str]) -> list[dict[str, Any]]:
    out = []
    for info in infos:
        node = full_node_name(info.node_name, info.node_namespace)
        out.append({"node": node, "in_launch": node in processes,
                    "process": processes.get(node), "qos": qos_dict(info.qos_profile)})
    return sorted(out, key=lambda e: e["node"])


def topic_entry(node: Any, name: str, types: list[str], processes: Mapping[str, str],
                hidden: set[str]) -> dict[str, Any]:
    publishers = [i for i in node.get_publishers_info_by_topic(name)
                  if full_node_name(i.node_name, i.node_namespace) not in hidden]
    subscribers = [i for i in node.get_subscriptions_info_by_topic(name)
                   if full_node_name(i.node_name, i.node_namespace) not in hidden]
    problems = []
    for pub in publishers:
        for sub in subscribers:
            sentence = pair_problem(name, full_node_name(pub.node_name, pub.node_namespace),
                                    pub.qos_profile,
                                    full_node_name(sub.node_name, sub.node_namespace),
                                    sub.qos_profile)
            if sentence is not None and sentence not in problems:
                problems.append(sentence)
    return {"name": name, "types": sorted(types),
            "publishers": _endpoints(publishers, processes),
            "subscribers": _endpoints(subscribers, processes),
            "qos_problems": problems}


OWN_NODE = re.compile(r"^tuilaunch(_\d+)?$")
"""The name of tuilaunch's own bridge nodes (ros/bridge.py)."""


def topics_graph(node: Any, processes: Mapping[str, str] | None = None,
                 only_node: str | None = None, hide_self: bool = True) -> dict[str, Any]:
    """`{"topics": [...]}` for every topic `node` has discovered.

    `processes` maps full node names (`/ns/name`) to this launch's process ids; `only_node`
    keeps the topics that node publishes or subscribes; `hide_self` leaves out tuilaunch's own
    endpoints (the inspector's rate and echo subscriptions), and topics only it uses."""
    processes = processes or {}
    hidden = {full_node_name(node.get_name(), node.get_namespace())} if hide_self else set()
    if hide_self:  # every tuilaunch's bridge (a session's server, each TUI: tuilaunch_PID)
        hidden |= {full_node_name(name, namespace) for name, namespace in
                   node.get_node_names_and_namespaces() if OWN_NODE.match(name)}
    topics = []
    for name, types in sorted(node.get_topic_names_and_types()):
        entry = topic_entry(node, name, list(types), processes, hidden)
        if not entry["publishers"] and not entry["subscribers"]:
            continue
        if only_node is not None and not node_uses(entry, only_node):
            continue
        topics.append(entry)
    return {"topics": topics}


def node_uses(entry: Mapping[str, Any], node: str) -> bool:
    """Whether the node (full name) publishes or subscribes this topic entry."""
    return any(e["node"] == node for e in (*entry["publishers"], *entry["subscribers"]))


def filter_node(graph: Mapping[str, Any], node: str) -> dict[str, Any]:
    """One node's topics out of a `topics_graph` result."""
    return {"topics": [t for t in graph["topics"] if node_uses(t, node)]}
