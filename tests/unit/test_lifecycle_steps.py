"""`]]` typed faster than a lifecycle node moves: configure, then activate, one after the
other (a node refuses a transition while one runs)."""

from __future__ import annotations

import asyncio

from tuilaunch.tui.nodes.lifecycle_steps import LifecycleSteps


def test_two_steps_up_from_unconfigured_configure_then_activate_one_after_the_other():
    steps = LifecycleSteps()
    asked: list[str] = []
    running: list[str] = []

    async def node(transition: str) -> bool:
        assert not running, f"{transition} asked while {running} ran"
        running.append(transition)
        await asyncio.sleep(0.01)
        running.pop()
        asked.append(transition)
        return True

    async def scenario() -> None:
        reported = "unconfigured"  # the node's events have not moved yet
        first = steps.step("lc", reported, "up")
        assert first == "configure"
        one = asyncio.ensure_future(steps.take("lc", first, lambda: node(first)))
        second = steps.step("lc", reported, "up")  # from where the first step leads
        assert second == "activate"
        two = asyncio.ensure_future(steps.take("lc", second, lambda: node(second)))
        assert steps.step("lc", reported, "up") is None  # active: nothing above
        assert steps.step("lc", reported, "down") == "deactivate"
        await asyncio.gather(one, two)
        # done, and the node's events not yet heard: still from where the steps led
        assert steps.step("lc", "unconfigured", "down") == "deactivate"
        # once they say it, from what they say
        assert steps.step("lc", "active", "down") == "deactivate"
        assert steps.step("lc", "inactive", "up") == "activate"

    asyncio.run(scenario())
    assert asked == ["configure", "activate"]


def test_a_refused_step_leaves_the_state_to_the_nodes_events():
    steps = LifecycleSteps()

    async def refused() -> bool:
        return False

    async def scenario() -> None:
        assert steps.step("lc", "active", "down") == "deactivate"
        assert await steps.take("lc", "deactivate", refused) is False
        assert steps.step("lc", "active", "down") == "deactivate"  # not "cleanup"

    asyncio.run(scenario())
