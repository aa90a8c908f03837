"""The tree, the detail line above it and the status line follow what the session says
(memory_port.py: the events are told by the test), each as a user reads them: a row's
icon and words, a group's counts, a crash's reason, the header's counts and values."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.unit.test_app_pilot import detail, following, pane, row, select, status, until
from tuilaunch.engine.run.events import (
    ActionFinished,
    ExitCause,
    Failed,
    ProcessExited,
    Respawning,
    Started,
    Stopping,
)
from tuilaunch.tui.nodes import respawn_countdown


async def test_every_row_waits_until_the_session_starts_it(tmp_path: Path) -> None:
    async with following(tmp_path, started=False) as (app, pilot, port):
        assert row(app, "talker-1").startswith("… ")
        assert "waiting" in row(app, "talker-1")
        # a process waiting for its trigger says for what, on its row
        assert "waiting (1 s after talker-1 starts" in row(app, "configurable-3"), \
            row(app, "configurable-3")
        assert "5 waiting" in status(app)
        port.tell(Started("talker-1", pid=4242))
        await until(pilot, lambda: row(app, "talker-1") == "● talker-1 running pid 4242",
                    "talker-1's row running with its pid")
        await until(pilot, lambda: "1 running  4 waiting" in status(app),
                    "the status line counting 1 running, 4 waiting")


async def test_the_header_names_the_session_file_counts_and_values(tmp_path: Path) -> None:
    async with following(tmp_path, arguments={"robot": "r2", "listener": "false"}) \
            as (app, _pilot, _port):
        assert status(app) == \
            "[bringup] bringup.py  4 running  1 skipped  robot:=r2 listener:=false"


async def test_a_skipped_node_says_which_condition_skips_it(tmp_path: Path) -> None:
    async with following(tmp_path, arguments={"listener": "false"}) as (app, pilot, _port):
        assert row(app, "listener-2") == \
            "○ listener-2 skipped (if $(var listener) = 'false')"
        select(app, "listener-2")
        await until(pilot, lambda: detail(app).startswith("listener-2"), "its detail line")
        assert detail(app) == \
            "listener-2 (/r1/<listener>): skipped (if $(var listener) = 'false')"


async def test_a_crash_is_failed_with_its_reason_on_the_detail_line(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        select(app, "talker-1")
        port.tell(ProcessExited("talker-1", pid=1000, code=-11, reason="killed by SIGSEGV",
                                cause=ExitCause.CRASHED))
        await until(pilot, lambda: row(app, "talker-1").startswith("✗ talker-1 failed"),
                    "talker-1's row failed")
        assert "killed by SIGSEGV" in row(app, "talker-1")
        await until(pilot, lambda: "killed by SIGSEGV" in detail(app), "the reason above")
        assert detail(app) == \
            "talker-1 (/r1/<talker>): failed (killed by SIGSEGV, pid 1000)"
        await until(pilot, lambda: "4 running  1 failed" in status(app), "counted failed")


async def test_a_node_that_fails_to_start_says_why(tmp_path: Path) -> None:
    async with following(tmp_path, started=False) as (app, pilot, port):
        select(app, "monitor-5")
        port.tell(Failed("monitor-5", reason="executable 'monitor' not found"))
        await until(pilot, lambda: "executable 'monitor' not found" in detail(app),
                    "the failure's reason on the detail line")
        assert row(app, "monitor-5").startswith("✗ monitor [monitor-5] failed")
        await until(pilot, lambda: "1 failed" in status(app), "the status line's count")


async def test_a_clean_end_is_exited_not_failed(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        port.tell(ProcessExited("monitor-5", pid=1004, code=0, reason="exit code 0"))
        await until(pilot, lambda: row(app, "monitor-5").startswith("■ "),
                    "monitor-5's row exited")
        assert "exited" in row(app, "monitor-5")
        await until(pilot, lambda: "4 running  1 exited" in status(app), "counted exited")
        assert "failed" not in status(app)


async def test_a_stop_asked_for_is_exited_and_its_pane_says_stopped(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        select(app, "talker-1")
        await pilot.press("s")
        await until(pilot, lambda: ("stop", {"process": "talker-1"}) in port.asked,
                    "the stop asked")
        port.tell(Stopping("talker-1", pid=1000),
                  ProcessExited("talker-1", pid=1000, code=-2, reason="killed by SIGINT",
                                cause=ExitCause.ASKED))
        await until(pilot, lambda: row(app, "talker-1").startswith("■ talker-1 exited"),
                    "talker-1 exited, not failed")
        await until(pilot, lambda: "process stopped [pid 1000, killed by SIGINT]" in pane(app),
                    "the pane saying it was stopped, not that it died")
        assert "failed" not in status(app)


async def test_a_respawn_counts_down_on_its_row_and_in_the_status_line(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # the wait is counted on a clock the test moves: on the real one a loaded machine may
    # look at the row only after its "30 s" or "29 s" has passed (the row skips a second
    # when the timer comes late, as it should)
    now = [1000.0]
    monkeypatch.setattr(respawn_countdown, "monotonic", lambda: now[0])
    async with following(tmp_path) as (app, pilot, port):
        select(app, "talker-1")
        port.tell(ProcessExited("talker-1", pid=1000, code=1, reason="exit code 1",
                                cause=ExitCause.CRASHED),
                  Respawning("talker-1", reason="respawn in 30 s",
                             data={"try": 2, "delay": 30.0}))
        await until(pilot, lambda: "respawning (try 2 in 30 s)" in row(app, "talker-1"),
                    "the wait on the row")
        assert row(app, "talker-1").startswith("↻ ")
        await until(pilot, lambda: "1 respawning" in status(app), "the status line's count")
        assert "try 2 in 30 s" in row(app, "talker-1")  # no second has passed yet
        now[0] += 1.0
        await until(pilot, lambda: "try 2 in 29 s" in row(app, "talker-1"),
                    "the wait counted down a second later")
        await until(pilot, lambda: "try 2 in 29 s" in detail(app), "the detail line alike")
        now[0] += 2.5
        await until(pilot, lambda: "try 2 in 27 s" in row(app, "talker-1"),
                    "a late tick says what is left, skipping the second it missed")
        port.tell(Started("talker-1", pid=2000))
        await until(pilot, lambda: row(app, "talker-1") == "● talker-1 running pid 2000",
                    "back, the wait gone")
        await until(pilot, lambda: "respawning" not in status(app), "no respawning counted")


async def test_a_groups_detail_counts_its_running_stopping_and_failed(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        select(app, "ns /r1/control")
        await until(pilot, lambda: detail(app).startswith("ns /r1/control"), "the group")
        assert "1 of 1 processes running" in detail(app)
        select(app, "ns /r1")
        await until(pilot, lambda: detail(app).startswith("ns /r1:"), "the robot's group")
        port.tell(Stopping("talker-1", pid=1000), Stopping("service_server-4", pid=1003),
                  ProcessExited("monitor-5", pid=1004, code=1, reason="exit code 1",
                                cause=ExitCause.CRASHED))
        await until(pilot, lambda: detail(app) ==
                    "ns /r1: 2 of 5 processes running, 2 stopping, 1 failed",
                    "the group's counts, stopping and failed said")


async def test_the_root_and_all_nodes_rows_say_what_they_hold(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, _port):
        app.launch_tree.move_cursor(app.launch_tree.root)
        await until(pilot, lambda: detail(app) == "bringup.py: 5 of 5 processes running",
                    "the root counts every process")
        select(app, "all nodes")
        await until(pilot, lambda: detail(app) ==
                    "all nodes: every process's output, with its id", "all nodes")


async def test_an_action_row_says_waiting_then_done(tmp_path: Path) -> None:
    async with following(tmp_path) as (app, pilot, port):
        action = next(a.id for a in app.session.plan.actions if "reset" in str(a.target))
        select(app, "call /r1/reset")
        await until(pilot, lambda: detail(app).startswith("call /r1/reset"), "the action")
        assert detail(app) == f"call /r1/reset [{action}]: waiting"
        port.tell(ActionFinished(action, reason="done"))
        await until(pilot, lambda: detail(app).startswith(f"call /r1/reset [{action}]: done"),
                    "the action done")


async def test_a_long_failure_reason_is_read_whole_at_80_columns(tmp_path: Path) -> None:
    missing = "executable 'no-such-program-" + "x" * 60 + "' not found"
    async with following(tmp_path, started=False) as (app, pilot, port):
        select(app, "monitor-5")
        port.tell(Failed("monitor-5", reason=missing))
        # the detail line wraps rather than cut the reason at the screen's edge
        await until(pilot, lambda: missing in detail(app), "the reason above the tree")
        await until(pilot, lambda: app.detail_bar.size.height >= 2, "the line wrapped")
        await until(pilot, lambda: any(missing in line for line in pane(app)),
                    "tuilaunch's own line in the pane")
