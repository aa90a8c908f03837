"""A lost link's line says the attempt to reconnect under way: one that hangs (ssh's 15 s
before it notices a host that is gone, then a greeting's 30) is not hidden behind the
reason of the attempt before it. The line at 80 columns, the TUI's status line over an
in-memory session (memory_port.py), and the fleet's root row."""

from __future__ import annotations

import re
import time
from pathlib import Path

from tests.unit.test_app_pilot import following, status, until
from tuilaunch.client.link import lost_link_line, relink_words

REFUSED = "cannot reach robot1: connect to host 127.0.0.1 port 51697: Connection refused"


def test_between_tries_the_line_is_as_before() -> None:
    assert lost_link_line("robot1", "far", "ssh exit status 255", 1, None, 80) == \
        "link to robot1 lost · reconnecting · far · R: now · ssh exit status 255"


def test_an_attempt_under_way_is_said_with_its_number_and_time_and_the_last_reason() -> None:
    line = lost_link_line("robot1", "far", REFUSED, 3, 12.4, 80)
    assert line == "link to robot1 lost · retrying (attempt 3, 12 s) · last: … Connection refused"
    assert len(line) <= 80
    # where there is room, the session's name and more of the reason
    assert lost_link_line("robot1", "far", REFUSED, 3, 12.4, 160) == \
        f"link to robot1 lost · retrying (attempt 3, 12 s) · far · last: {REFUSED}"
    assert relink_words(2, 1.2) == "retrying (attempt 2, 1 s)"
    assert relink_words(2, None) == "reconnecting"
    # one refused at once does not flash the line at every try
    assert relink_words(2, 0.3) == "reconnecting"
    assert lost_link_line("robot1", "far", "ssh exit status 255", 2, 0.3, 80).startswith(
        "link to robot1 lost · reconnecting · far · R: now · ")


async def test_the_status_line_counts_the_attempt_under_way(tmp_path: Path) -> None:
    async with following(tmp_path, host="robot1") as (app, pilot, port):
        port.link_lost = "link to robot1 lost (ssh exit status 255)"
        port.lost_reason = "ssh exit status 255"
        await until(pilot, lambda: status(app).startswith(
            "link to robot1 lost · reconnecting · bringup · R: now · ssh exit status 255"),
            "between tries")
        port.attempt, port.attempt_since = 1, time.monotonic() - 12.2
        # its seconds as drawn (a busy machine draws a second late: 12 s or more)
        await until(pilot, lambda: re.match(
            r"link to robot1 lost · retrying \(attempt 1, 1\d s\) · last: ssh exit status "
            "255", status(app)),
            "the attempt under way, its seconds (no room for the name at 80 columns)")
        shown = status(app)
        await until(pilot, lambda: status(app) != shown, "its seconds go on")
        port.lost_reason, port.attempt_since = REFUSED, None  # it failed: the next waits
        await until(pilot, lambda: status(app).startswith(
            "link to robot1 lost · reconnecting · bringup · R: now · "), "between tries")
        assert status(app).split("  ")[0].endswith("Connection refused")


def test_the_fleets_root_row_says_the_attempt_and_its_latest_reason() -> None:
    from types import SimpleNamespace

    from tuilaunch.tui.session_view import relinking

    port = SimpleNamespace(attempt=2, attempt_since=None, lost_reason="ssh exit status 255",
                           link_lost="link to nuc lost (ssh exit status 255)")
    assert relinking(port) == "reconnecting (R: now)"  # type: ignore[arg-type]
    port.attempt_since = time.monotonic() - 5.2
    assert relinking(port) == "retrying (attempt 2, 5 s)"  # type: ignore[arg-type]
    port.lost_reason = REFUSED  # the latest reason, not the one the row already says
    assert relinking(port) == \
        f"retrying (attempt 2, 5 s), last: {REFUSED}"  # type: ignore[arg-type]
