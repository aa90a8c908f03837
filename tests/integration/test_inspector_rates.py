"""Rates, bandwidth and echo of topics published by real nodes at known rates and QoS.

The bands are loose on purpose (a busy shared machine): accuracy figures belong in bench/."""

from __future__ import annotations

import asyncio
import threading
from typing import Any

import pytest

from tuilaunch.engine.ros.bridge import RosBridge, RosError
from tuilaunch.engine.ros.graph.echo import Throttle, message_yaml
from tuilaunch.engine.ros.graph.rates import message_class
from tuilaunch.engine.ros.messages import MessageError

from .inspector_helpers import eventually, ros_nodes, run

NS = "/rates_test"
PUBLISHERS = (
    ["fast", "--namespace", NS, "--pub", "fast", "--rate", "100"],
    ["slow", "--namespace", NS, "--pub", "slow", "--rate", "1", "--best-effort"],
    ["latched", "--namespace", NS, "--pub", "latched", "--rate", "20", "--transient-local"],
)


async def reading(bridge: RosBridge, topic: str, messages: int) -> dict[str, Any]:
    async def check() -> dict[str, Any] | None:
        result = (await bridge.read_rates(topic))[topic]
        return result if result["messages"] >= messages else None
    return await eventually(check, 60, f"{messages} messages on {topic}")


def test_rates_of_several_topics_at_once_with_matching_qos():
    async def scenario(bridge: RosBridge) -> tuple[dict[str, Any], ...]:
        topics = [f"{NS}/fast", f"{NS}/slow", f"{NS}/latched"]
        await bridge.start_rates(topics, window_s=5.0, wait=30)
        fast = await reading(bridge, f"{NS}/fast", 150)
        slow = await reading(bridge, f"{NS}/slow", 3)  # best effort: matched, or nothing
        latched = await reading(bridge, f"{NS}/latched", 30)  # transient local publisher
        await bridge.stop_rates([f"{NS}/fast"])
        left = sorted(await bridge.read_rates())
        await bridge.stop_rates()
        return fast, slow, latched, left, await bridge.read_rates()

    with ros_nodes(*PUBLISHERS):
        fast, slow, latched, left, after_stop = run(scenario)
    assert set(fast) == {"topic", "rate_hz", "bytes_per_s", "messages", "window_s"}
    assert fast["topic"] == f"{NS}/fast"
    assert 50 <= fast["rate_hz"] <= 150
    assert fast["bytes_per_s"] > 0 and 0 < fast["window_s"] <= 5.0
    assert 0.5 <= slow["rate_hz"] <= 1.5
    assert 10 <= latched["rate_hz"] <= 30
    assert left == [f"{NS}/latched", f"{NS}/slow"]
    assert after_stop == {}


def test_many_topics_each_read_at_its_own_rate_and_stop_lets_go_of_them():
    rates = {f"{NS}/many_{hz}": hz for hz in (5, 10, 25, 50)}

    async def scenario(bridge: RosBridge) -> tuple[dict[str, Any], list[str], Any]:
        await bridge.start_rates(list(rates), window_s=5.0, wait=30)
        results = {t: await reading(bridge, t, 2 * hz) for t, hz in rates.items()}
        await bridge.stop_rates()

        async def released() -> bool:
            counts = [await asyncio.to_thread(bridge.node.count_subscribers, t) for t in rates]
            return counts == [0] * len(rates) and not meter_threads()
        await eventually(released, 60, "subscriptions and the meter's thread gone")
        left = await bridge.read_rates()
        # measuring again after everything stopped
        await bridge.start_rates([f"{NS}/many_50"], window_s=5.0, wait=30)
        again = await reading(bridge, f"{NS}/many_50", 20)
        return results, sorted(left), again

    publishers = [[f"many_{hz}", "--namespace", NS, "--pub", f"many_{hz}", "--rate", str(hz)]
                  for hz in rates.values()]
    with ros_nodes(*publishers):
        results, left, again = run(scenario)
    for topic, hz in rates.items():
        assert 0.5 * hz <= results[topic]["rate_hz"] <= 1.5 * hz, (topic, results[topic])
    assert left == []
    assert 25 <= again["rate_hz"] <= 75


def meter_threads() -> list[threading.Thread]:
    return [t for t in threading.enumerate() if t.name == "rate meter"]


def test_a_bridge_closed_while_measuring_ends_its_meter_before_the_node():
    """Closing a bridge that still measures (a TUI quit on the Topics tab) stops the
    meter's thread before the node and the context go: a thread left serving let go of
    its subscriptions after them, and their destruction then crashed the process."""
    async def scenario(bridge: RosBridge) -> dict[str, Any]:
        await bridge.start_rates([f"{NS}/closing"], window_s=5.0, wait=30)
        return await reading(bridge, f"{NS}/closing", 5)

    with ros_nodes(["closing", "--namespace", NS, "--pub", "closing", "--rate", "50"]):
        assert run(scenario)["messages"] >= 5
        assert meter_threads() == []  # ended by close itself, not some time after it


def test_bandwidth_follows_message_size():
    async def scenario(bridge: RosBridge) -> dict[str, Any]:
        await bridge.start_rates([f"{NS}/big"], window_s=5.0, wait=30)
        return await reading(bridge, f"{NS}/big", 40)

    with ros_nodes(["big", "--namespace", NS, "--pub", "big", "--rate", "20",
                    "--array", "2500"]):
        result = run(scenario)
    # 2500 int32 = 10 kB a message, 20 a second: about 200 kB/s
    assert 100_000 <= result["bytes_per_s"] <= 400_000


def test_a_topic_nobody_publishes_is_one_line_not_a_hang():
    async def scenario(bridge: RosBridge) -> None:
        await bridge.start_rates([f"{NS}/nobody"], wait=1.0)

    with pytest.raises(RosError) as caught:
        run(scenario)
    assert str(caught.value) == f"topic {NS}/nobody has no publisher (waited 1 s)"


def test_a_type_not_installed_says_which_package_to_install():
    with pytest.raises(MessageError) as caught:
        message_class("velodyne_msgs/msg/VelodyneScan")
    assert str(caught.value) == ("velodyne_msgs/msg/VelodyneScan: install the Python package "
                                 "ros-jazzy-velodyne-msgs")


def test_echo_prints_yaml_messages_separated_like_ros2_topic_echo():
    async def scenario(bridge: RosBridge) -> str:
        echo = await bridge.start_echo(f"{NS}/fast", wait=30)
        taken: list[str] = []

        async def check() -> bool:
            taken.append(echo.take_yaml())
            return "".join(taken).count("---\n") >= 3
        await eventually(check, 60, "three echoed messages")
        await bridge.stop_echo(echo)
        return "".join(taken)

    with ros_nodes(PUBLISHERS[0]):
        text = run(scenario)
    first, second, *_ = text.split("---\n")
    assert first.startswith("data: hello ") and second.startswith("data: hello ")


def test_long_arrays_are_cut_with_a_count():
    from std_msgs.msg import Int32MultiArray

    text = message_yaml(Int32MultiArray(data=list(range(1000))))
    assert text.endswith("---\n")
    assert "- 127\n" in text and "- 128\n" not in text
    assert "... (1000 items)" in text
    assert "- 999" in message_yaml(Int32MultiArray(data=list(range(1000))), None)


def test_throttle_lets_a_few_messages_a_second_through():
    throttle = Throttle(per_second=4)
    passed = [t for t in (i / 16 for i in range(32)) if throttle.ready(now=t)]
    assert passed == [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75]


def test_a_transient_local_history_is_not_counted_as_messages_published_now():
    """/rosout, /tf_static, maps: a new subscription is handed the kept history at once.
    Counted, 50 kept messages inflate a 2 Hz topic's rate tenfold; the Topics tab's windows
    and `hz`'s message windows count only what is published after they matched, as ros2
    topic hz does."""
    from tuilaunch.engine.ros.graph.rates import RateMeter

    topic = f"{NS}/kept"

    async def scenario(bridge: RosBridge) -> tuple[dict[str, Any], dict[str, Any]]:
        await bridge.start_rates([topic], window_s=10.0, wait=30)
        meter = RateMeter(bridge.node)
        await meter.start(topic, wait=30, messages=100)
        tab = await reading(bridge, topic, 3)

        async def counted() -> dict[str, Any] | None:
            result = meter.read(topic)[topic]
            return result if result["messages"] >= 3 else None
        hz = await eventually(counted, 60, "3 messages counted by hz's window")
        meter.stop_all()
        await bridge.stop_rates()
        return tab, hz

    with ros_nodes(["kept", "--namespace", NS, "--pub", "kept", "--rate", "2",
                    "--transient-local", "--depth", "100", "--burst", "50"]):
        tab, hz = run(scenario)
    assert tab["messages"] < 50 and tab["rate_hz"] < 5  # published at 2 Hz
    assert hz["messages"] < 50 and hz["rate_hz"] < 5
