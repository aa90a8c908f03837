"""What a flood keeps off a display is not missed: the session says where each run of lines
it did not send is in the process's log file, and a pane scrolled back to it reads them.

A real session server runs a process that floods once a file appears (after the client is
subscribed); a client subscribed for few lines a batch, as a display over an ssh link is,
gets most of the flood as `dropped` notices.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from textual.pilot import Pilot

from tuilaunch.client.remote_supervisor import RemoteSupervisor
from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.supervisor.supervisor import Event
from tuilaunch.engine.run.vocabulary.requests import ReadLog
from tuilaunch.tui.app import TuiLaunchApp, make_app
from tuilaunch.tui.output_store import View

from .session_steps import stop_here
from .test_sessions import detached_with, runtime, tl  # noqa: F401  (runtime: a fixture)
from .test_tui import until

COUNT = 3000

FLOOD = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='flood', cmd=[
        'sh', '-c', 'while [ ! -e {go} ]; do sleep 0.05; done; seq 1 {count}; exec sleep 600'])])
"""


def flood_session(write, tmp_path: Path) -> tuple[str, str, Path, Path]:
    """A session whose `flood-1` prints 1..COUNT once `go` exists: (name, launch file, its
    log folder, go)."""
    go = tmp_path / "go"
    path = str(write(FLOOD.format(go=go, count=COUNT)))
    name, log_dir = detached_with(path, "flood-1")
    return name, path, log_dir, go


@asynccontextmanager
async def few_lines_a_batch(app: TuiLaunchApp) -> AsyncIterator[Pilot]:
    """The TUI, subscribed to its session for 30 lines a batch (as a display over a link is
    sent a pane's worth): under the flood the session leaves most lines out. Its own
    buffer then holds what comes, as it does over a link."""
    held = app.buffer.max_lines
    app.buffer.max_lines = 30  # what it subscribes with
    async with app.run_test(size=(80, 24)) as pilot:
        await until(pilot, lambda: app.supervisor is not None)
        app.buffer.max_lines = held
        yield pilot


def test_every_line_kept_from_a_client_is_where_its_gap_says(runtime, write, tmp_path):  # noqa: F811
    name, path, _, go = flood_session(write, tmp_path)

    async def scenario() -> list[str]:
        client = await RemoteSupervisor.open(name, Session(path, {}), max_lines=20,
                                             interval=0.2)
        events: list[Event] = []
        client.subscribe(lambda event: events.append(event) if event.process == "flood-1"
                         and event.kind in ("output", "dropped") else None)
        task = asyncio.ensure_future(client.run())
        go.touch()

        def told() -> int:
            return sum(len(e.lines) if e.kind == "output" else e.code or 0 for e in events)

        for _ in range(1200):
            if told() >= COUNT:
                break
            await asyncio.sleep(0.05)
        assert told() == COUNT
        gaps = [e for e in events if e.kind == "dropped"]
        assert gaps, "the client was sent every line: no flood to speak of"
        # each gap read back from where it says: with the lines sent, every line, in order
        seen: list[str] = []
        for event in events:
            if event.kind == "output":
                seen += event.lines
                continue
            where = event.data or {}
            page = await client.request(ReadLog(process="flood-1", start=where["start"],
                                                skip=where["skip"], limit=event.code))
            seen += [text for _, _, text in page["lines"]]
        await client.detach()
        await asyncio.wait_for(task, 60)
        return seen

    assert asyncio.run(scenario()) == [str(i) for i in range(1, COUNT + 1)]
    stop_here(name)


def test_a_pane_scrolled_back_reads_the_lines_a_flood_kept_off_it(runtime, write,  # noqa: F811
                                                                   tmp_path):
    """Scrolled back, a line stands for each run of lines not drawn, and is replaced by
    them once on screen: paging down from the top, the pane has every line in order."""
    name, path, log_dir, go = flood_session(write, tmp_path)

    async def scenario() -> None:
        app = make_app(path, {}, log_dir, session_name=name)
        async with few_lines_a_batch(app) as pilot:
            go.touch()
            panel = app.output_panel
            store = app.store

            def flood() -> list:
                return [line for line in store.lines(View("flood-1")) if not line.event
                        or line.gap is not None]

            await until(pilot, lambda: any(line.text == str(COUNT) for line in flood()))
            assert any(line.gap is not None for line in flood())
            assert "not drawn" in str(panel.query_one("#output-status").render())
            view = panel.line_view
            view.focus()
            await pilot.press("home")

            def whole() -> bool:
                return [line.text for line in flood()] == [str(i) for i in range(1, COUNT + 1)]

            for _ in range(2000):
                if whole():
                    break
                await pilot.press("home" if view.following else "pagedown")
                await pilot.pause(0.02)
            assert whole()
            shown = [line.text for line in view.lines if line.process == "flood-1"
                     and not line.event]
            assert shown == [str(i) for i in range(1, COUNT + 1)]
            assert "not drawn" not in str(panel.query_one("#output-status").render())

    asyncio.run(scenario())
    stop_here(name)


def test_a_gap_whose_log_file_is_gone_says_so_and_stays(runtime, write, tmp_path):  # noqa: F811
    """The log file removed meanwhile (a cleaner, a full disk's rescue): scrolled back to
    the gap, the pane says its lines are no longer there and keeps the line saying how
    many were not drawn, rather than dropping it without a word."""
    name, path, log_dir, go = flood_session(write, tmp_path)

    async def scenario() -> None:
        app = make_app(path, {}, log_dir, session_name=name)
        async with few_lines_a_batch(app) as pilot:
            go.touch()

            def gaps() -> list:
                return [line for line in app.store.lines(View("flood-1")) if line.gap]

            await until(pilot, lambda: any(line.text == str(COUNT)
                                           for line in app.store.lines(View("flood-1"))))
            before = gaps()
            assert before
            (log_dir / "flood-1.log").unlink()
            app.output_panel.line_view.focus()
            await pilot.press("home")
            await until(pilot, lambda: any("no longer has the lines not drawn" in n.message
                                           for n in app._notifications))
            assert gaps()[0] is before[0]

    asyncio.run(scenario())
    stop_here(name)
