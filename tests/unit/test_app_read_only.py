"""A read-only view (`attach --read-only`, `serve --read-only`) over an in-memory session:
its footer offers no key it refuses, and such a key typed out of habit is answered with one
line, nothing asked of the session."""

from __future__ import annotations

from pathlib import Path

from tests.unit.test_app_pilot import following, footer, select, toasts, until

CHANGES = ("stop", "restart", "start", "apply", "log_level", "transition")


async def test_the_footer_offers_none_of_the_keys_it_refuses(tmp_path: Path) -> None:
    async with following(tmp_path, read_only=True) as (app, pilot, _port):
        select(app, "talker-1")
        # the footer is drawn anew for the row (empty for a moment): read once it is there
        await until(pilot, lambda: "Search" in footer(app), "the row's footer drawn")
        offered = footer(app)
        for refused in ("Stop", "Restart", "Start", "Type", "Debug", "Apply"):
            assert refused not in offered, offered
        assert "Search" in offered  # what only reads stays


async def test_a_refused_key_says_so_in_one_line_and_asks_nothing(tmp_path: Path) -> None:
    async with following(tmp_path, read_only=True) as (app, pilot, port):
        select(app, "talker-1")
        await pilot.press("s")
        await until(pilot, lambda: "read-only view: stopping a process is refused"
                    in toasts(app), "the stop's refusal")
        await pilot.press("r", "t", "f5")
        for said in ("restarting a process", "starting a process",
                     "relaunching with other arguments"):
            await until(pilot, lambda said=said: f"read-only view: {said} is refused"
                        in toasts(app), f"the refusal of {said}")
        assert not [op for op in port.ops() if op in CHANGES], port.asked


async def test_the_same_keys_act_where_the_view_is_not_read_only(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        select(app, "talker-1")
        await pilot.press("s")
        await until(pilot, lambda: "stop" in port.ops(), "the stop asked of the session")
        assert not any("read-only" in toast for toast in toasts(app))
