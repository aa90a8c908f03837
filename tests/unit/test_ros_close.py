"""A stop never waits forever on rclpy: its shutdown can hang inside the DDS library (seen
once under load: a writer's timer waiting for Fast DDS's event thread), and the session must
end all the same, saying why."""

from __future__ import annotations

import asyncio
import threading

import pytest

from tuilaunch.engine.ros import actions
from tuilaunch.engine.run.events import Event, Log


class HangingBridge:
    def __init__(self) -> None:
        self.released = threading.Event()

    def close(self) -> None:
        self.released.wait(30)  # as rcl_logging_fini did, stuck on the DDS lock


async def test_a_hung_rclpy_shutdown_ends_the_stop_and_is_said(
        monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(actions, "CLOSE_WITHIN", 0.3)
    monkeypatch.setattr(actions, "CLOSE_HUNG", threading.Event())
    said: list[Event] = []
    plugin = actions.RosActions(None, 5.0, said.append)
    bridge = HangingBridge()
    plugin._bridge = bridge  # made here, as on a launch's first service call
    try:
        await asyncio.wait_for(plugin.close(), timeout=20)
        assert actions.CLOSE_HUNG.is_set()
        assert [(e.level, e.reason) for e in said if isinstance(e, Log)] == [
            ("WARN", "rclpy did not shut down within 0.3 s (a hang in the DDS library): the "
                     "launch ends without it")]
    finally:
        bridge.released.set()


async def test_a_shutdown_that_ends_says_nothing(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(actions, "CLOSE_HUNG", threading.Event())
    said: list[Event] = []
    plugin = actions.RosActions(None, 5.0, said.append)
    bridge = HangingBridge()
    bridge.released.set()
    plugin._bridge = bridge
    await plugin.close()
    assert not actions.CLOSE_HUNG.is_set() and said == []
