"""Editing arguments: the preview says what would change; applying relaunches only that."""

from __future__ import annotations

import asyncio

from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.supervisor.supervisor import Supervisor

LAUNCH = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('extra', False)
    sl.declare_arg('word', 'a')
    sl.add_action(ExecuteProcess(cmd=['sleep', '600'], name='steady'))
    sl.add_action(ExecuteProcess(cmd=['sh', '-c', sl.arg('word') + '; sleep 600'], name='echo'))
    with sl.group(if_arg='extra'):
        sl.add_action(ExecuteProcess(cmd=['sleep', '601'], name='optional'))
    return sl.launch_description()
"""


def test_preview_names_what_would_start_and_stop_or_the_error(write, tmp_path):
    session = Session(str(write(LAUNCH)), {"word": "echo a"}, tmp_path / "params")
    preview = session.preview({"extra": "true", "word": "echo b"})
    assert preview.error is None and preview.diff is not None
    assert preview.diff.keep == ["steady-1"]
    assert preview.diff.stop == ["echo-2"]
    assert preview.diff.start == ["echo-2", "optional-3"]
    bad = session.preview({"extra": "perhaps"})
    assert bad.plan is None and bad.error is not None and "'extra' = 'perhaps'" in bad.error
    assert session.arguments == {"word": "echo a"}  # previews change nothing


def test_apply_keeps_unchanged_processes_running(write, tmp_path):
    session = Session(str(write(LAUNCH)), {"word": "echo a"}, tmp_path / "params")
    supervisor = Supervisor(session.plan, tmp_path / "log")
    events: list = []
    supervisor.subscribe(events.append)

    def pids() -> dict[str, int]:
        return {e.process: e.pid for e in events if e.kind == "started"}

    async def scenario() -> None:
        run = asyncio.ensure_future(supervisor.run(keep_alive=True))
        while len(pids()) < 2:
            await asyncio.sleep(0.05)
        before = pids()
        preview = session.preview({"extra": "true", "word": "echo b"},
                                  set(supervisor.states) & {"steady-1", "echo-2"})
        await supervisor.replace_plan(session.accept(preview))
        while len([e for e in events if e.kind == "started"]) < 4:
            await asyncio.sleep(0.05)
        after = pids()
        assert after["steady-1"] == before["steady-1"]  # untouched
        assert after["echo-2"] != before["echo-2"]  # restarted with the new command
        assert supervisor.states["optional-3"] == "running"
        out = [line for e in events if e.kind == "output" for line in e.lines]
        assert out.count("a") == 1 and out.count("b") == 1
        await supervisor.shutdown("done")
        await run

    asyncio.run(scenario())


ONE_SHOT = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('word', 'a')
    sl.add_action(ExecuteProcess(cmd=['echo', 'spawned once'], name='spawner'))
    sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'exit 3'], name='broken'))
    sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo ' + sl.arg('word') + '; sleep 600'],
                                 name='talker'))
    return sl.launch_description()
"""


def test_a_relaunch_leaves_unchanged_finished_processes_alone(write, tmp_path):
    """A spawner that did its job does not run again when an unrelated argument changes,
    and a failed process keeps its failure until the operator restarts it."""
    session = Session(str(write(ONE_SHOT)), {}, tmp_path / "params")
    supervisor = Supervisor(session.plan, tmp_path / "log")
    events: list = []
    supervisor.subscribe(events.append)

    def started(process: str) -> int:
        return len([e for e in events if e.kind == "started" and e.process == process])

    async def scenario() -> None:
        run = asyncio.ensure_future(supervisor.run(keep_alive=True))
        while not ("spawner-1" in supervisor.exit_codes and "broken-2" in supervisor.exit_codes
                   and started("talker-3")):
            await asyncio.sleep(0.05)
        states = dict(supervisor.states)
        running = {p for p, s in supervisor.states.items() if s == "running"}
        preview = session.preview({"word": "b"}, running)
        assert preview.diff is not None
        assert preview.diff.keep == ["spawner-1", "broken-2"]
        assert preview.diff.stop == ["talker-3"] and preview.diff.start == ["talker-3"]
        await supervisor.replace_plan(session.accept(preview))
        while started("talker-3") < 2:
            await asyncio.sleep(0.05)
        assert started("spawner-1") == 1 and started("broken-2") == 1
        assert supervisor.states["spawner-1"] == states["spawner-1"]
        assert supervisor.states["broken-2"] == states["broken-2"]
        await supervisor.shutdown("done")
        await run
        out = [line for e in events if e.kind == "output" for line in e.lines]
        assert out.count("spawned once") == 1

    asyncio.run(scenario())
