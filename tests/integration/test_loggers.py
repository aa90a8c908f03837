"""Logger levels of a running node through its logger service, or a clear 'no service'."""

from __future__ import annotations

import threading

import pytest

from tuilaunch.engine.ros.bridge import RosBridge, RosError
from tuilaunch.engine.ros.loggers import NoLoggerService

from .inspector_helpers import eventually, ros_nodes, run


def test_set_level_through_the_logger_service_takes_effect():
    with ros_nodes(["chatty", "--namespace", "/log_test", "--logger-service",
                    "--debug-ticks"]) as (proc,):
        lines: list[str] = []
        assert proc.stderr is not None
        reader = threading.Thread(target=lambda: lines.extend(proc.stderr or ()), daemon=True)
        reader.start()

        async def scenario(bridge: RosBridge) -> tuple[dict[str, str], dict[str, str]]:
            async def has_service() -> bool:
                return "/log_test/chatty/set_logger_levels" in dict(
                    await bridge.list_services())
            await eventually(has_service, 60, "the logger service")
            before = await bridge.get_logger_levels("/log_test/chatty")
            await bridge.set_logger_level("/log_test/chatty", "debug")

            async def debug_printed() -> bool:
                return any("debug tick" in line for line in lines)
            await eventually(debug_printed, 30, "a debug line from the node")
            with pytest.raises(RosError, match="'loud' is not a logger level"):
                await bridge.set_logger_level("/log_test/chatty", "loud")
            return before, await bridge.get_logger_levels("/log_test/chatty")

        before, after = run(scenario)
    assert before == {"log_test.chatty": "unset"} or before["log_test.chatty"] == "info"
    assert after == {"log_test.chatty": "debug"}


def test_a_node_without_the_service_says_so_and_names_the_restart():
    with ros_nodes(["plain", "--namespace", "/log_test"]):
        async def scenario(bridge: RosBridge) -> None:
            async def listed() -> bool:
                return "/log_test/plain" in await bridge.list_nodes()
            await eventually(listed, 60, "the node")
            await bridge.set_logger_level("/log_test/plain", "debug")

        with pytest.raises(NoLoggerService) as caught:
            run(scenario)
    message = str(caught.value)
    assert "\n" not in message
    assert "/log_test/plain has no logger service" in message and "--log-level" in message


def test_an_unknown_node_is_one_line():
    async def scenario(bridge: RosBridge) -> None:
        await bridge.set_logger_level("/log_test/nobody", "debug")

    with pytest.raises(RosError) as caught:
        run(scenario)
    assert str(caught.value) == "no node /log_test/nobody on the ROS graph"
