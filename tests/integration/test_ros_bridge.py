"""RosBridge against real rclpy nodes: what the service and parameter panels will use."""

from __future__ import annotations

import asyncio
import subprocess
import sys
import textwrap
from collections.abc import Iterator

import pytest

from tuilaunch.engine.packages import package_prefix
from tuilaunch.engine.ros.bridge import RosBridge, RosError
from tuilaunch.engine.ros.messages import MessageError, describe_fields, import_type

from .inspector_helpers import run

SLOW_SERVER = textwrap.dedent("""
    import signal, time, rclpy
    from std_srvs.srv import Trigger
    rclpy.init()
    # rclpy's SIGTERM handler would wait for a stuck answer to return (30 s) before the
    # node ends: the default handler ends it at once, as the fixture's terminate() expects
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    node = rclpy.create_node('slow', namespace='/bridge_test')
    def answer(request, response):
        time.sleep(30)
        return response
    node.create_service(Trigger, 'stuck', answer)
    print('ready', flush=True)
    rclpy.spin(node)
""")


@pytest.fixture(scope="module")
def nodes() -> Iterator[None]:
    lib = package_prefix("tuilaunch_demos") / "lib" / "tuilaunch_demos"
    ros = ["--ros-args", "-r", "__ns:=/bridge_test"]
    procs = [subprocess.Popen([str(lib / name), *ros], stdout=subprocess.PIPE, text=True)
             for name in ("service_server", "configurable")]
    procs.append(subprocess.Popen([sys.executable, "-c", SLOW_SERVER], stdout=subprocess.PIPE,
                                  text=True))
    try:
        for proc in procs:
            assert proc.stdout is not None
            assert proc.stdout.readline()  # each prints a first line once its node exists
        yield
    finally:
        for proc in procs:
            proc.terminate()
        # none outlives the module, even one that ignores SIGTERM or whose rclpy shutdown
        # is stuck (seen on a loaded machine): how they end is not under test
        for proc in procs:
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


async def _wait_listed(bridge: RosBridge, name: str) -> list[str]:
    # discovery of a node just started can take many seconds on a busy machine: the
    # deadline only guards against a hang
    deadline = asyncio.get_running_loop().time() + 60
    while True:
        found = await bridge.list_nodes()
        if name in found:
            return found
        if asyncio.get_running_loop().time() > deadline:
            raise AssertionError(f"{name} never listed within 60 s: {found}")
        await asyncio.sleep(0.1)


def test_graph_lists_nodes_and_services_with_types(nodes):
    async def scenario(bridge: RosBridge):
        await _wait_listed(bridge, "/bridge_test/configurable")
        found = await _wait_listed(bridge, "/bridge_test/service_server")
        assert "/bridge_test/slow" in found or "/bridge_test/slow" in await _wait_listed(
            bridge, "/bridge_test/slow")
        await bridge.wait_for_service("/bridge_test/enable", 60)
        return dict(await bridge.list_services())

    services = run(scenario)
    assert services["/bridge_test/enable"] == ["std_srvs/srv/SetBool"]
    assert services["/bridge_test/reset"] == ["std_srvs/srv/Trigger"]


def test_request_fields_are_described_for_forms():
    (data,) = describe_fields(import_type("std_srvs/srv/SetBool").Request)
    assert (data.name, data.type, data.default) == ("data", "boolean", False)
    fields = describe_fields(import_type("rcl_interfaces/srv/DescribeParameters").Request)
    assert [(f.name, f.is_sequence) for f in fields] == [("names", True)]


def test_call_service_builds_the_request_and_returns_the_response(nodes):
    async def scenario(bridge: RosBridge):
        first = await bridge.call_service("/bridge_test/enable", {"data": True}, wait=60,
                                          timeout=30)
        with pytest.raises(MessageError, match="field 'dat' does not exist"):
            await bridge.call_service("/bridge_test/enable", {"dat": True}, wait=60)
        with pytest.raises(MessageError, match="field 'data' needs a boolean, got 'yes'"):
            await bridge.call_service("/bridge_test/enable", {"data": "yes"}, wait=60)
        return first

    assert run(scenario) == ({"data": True}, {"success": True, "message": "enabled"})


def test_parameters_listed_described_set_and_refused_with_reasons(nodes):
    async def scenario(bridge: RosBridge):
        await bridge.wait_for_service("/bridge_test/configurable/set_parameters", 60)
        described = {p.name: p for p in await bridge.describe_parameters(
            "/bridge_test/configurable", timeout=30)}
        results = await bridge.set_parameters("/bridge_test/configurable", {
            "mode": "dock", "speed": 9.0, "robot_id": 3, "gains": [1, 2, 3],
            "label": "x"})
        # types come from the values, as simple_launch documents: an int list is no
        # double array, while a float list is
        results += await bridge.set_parameters("/bridge_test/configurable",
                                               {"gains": [1.0, 2.0, 3.0]})
        refused = await bridge.set_parameters("/bridge_test/configurable", {"mode": "fly"})
        after = await bridge.get_parameters("/bridge_test/configurable", ["mode", "gains"])
        return described, results, refused, after

    described, results, refused, after = run(scenario)
    speed = described["speed"]
    assert (speed.type, speed.value, speed.description) == ("float", 1.0, "cruise speed [m/s]")
    assert described["robot_id"].read_only and described["gains"].type == "float[]"
    outcome = {(r.name, r.successful): r.reason for r in results}
    assert outcome[("mode", True)] == "" and outcome[("label", True)] == ""
    assert "Wrong parameter type" in outcome[("gains", False)]
    assert outcome[("gains", True)] == ""
    outcome = {r.name: (r.successful, r.reason) for r in results}
    assert not outcome["speed"][0] and "out of range" in outcome["speed"][1]
    assert not outcome["robot_id"][0] and "read-only" in outcome["robot_id"][1]
    assert refused[0].reason == "mode must be idle, patrol or dock, not 'fly'"
    assert after == {"mode": "dock", "gains": [1.0, 2.0, 3.0]}


def test_every_call_has_a_timeout(nodes):
    async def scenario(bridge: RosBridge):
        await bridge.wait_for_service("/bridge_test/stuck", 60)
        with pytest.raises(RosError, match="did not answer within 1 s"):
            await bridge.call_service("/bridge_test/stuck", {}, timeout=1)
        with pytest.raises(RosError, match="is not available"):
            await bridge.list_parameters("/bridge_test/nobody", timeout=0.5)
        with pytest.raises(RosError, match="did not appear"):
            await bridge.wait_for_service("/bridge_test/never", 0.5)

    run(scenario)


CLOCK_PUBLISHER = textwrap.dedent("""
    import rclpy
    from rosgraph_msgs.msg import Clock
    rclpy.init()
    node = rclpy.create_node('sim_clock')
    node.create_publisher(Clock, '/clock', 10)
    print('ready', flush=True)
    rclpy.spin(node)
""")


def test_use_sim_time_auto_follows_a_live_clock_publisher(monkeypatch):
    from tuilaunch.engine.describe.python.sim_clock import clock_is_published

    monkeypatch.delenv("TUILAUNCH_SIM_TIME", raising=False)
    clock_is_published.cache_clear()
    assert clock_is_published() is False
    publisher = subprocess.Popen([sys.executable, "-c", CLOCK_PUBLISHER], stdout=subprocess.PIPE,
                                 text=True)
    try:
        assert publisher.stdout is not None and publisher.stdout.readline()
        clock_is_published.cache_clear()
        # the probe answers as soon as it discovers the publisher; the bound is for a
        # loaded machine, where discovery can take seconds
        assert clock_is_published(30.0) is True
    finally:
        publisher.terminate()
        try:
            publisher.wait(timeout=5)
        except subprocess.TimeoutExpired:  # rclpy's shutdown stuck on a loaded machine
            publisher.kill()
            publisher.wait()
        clock_is_published.cache_clear()
