"""The supervisor's parts, each made and driven alone. Its collaborators: the Respawner's
policy and backoff, the Stopper's escalation on a real process group, the TriggerBook's
handlers and flags, and Placing's answer to which side runs what. Its behaviours, over a
real core and real processes, each handed only what it calls: PlanActions performing a
timer's actions, Starting starting a process and following it to its end, Ending shutting
the launch down, Interacting typing into a process's terminal."""

from __future__ import annotations

import asyncio
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from tuilaunch.engine import load_file, resolve
from tuilaunch.engine.describe.entities import TriggerOn
from tuilaunch.engine.errors import LaunchError
from tuilaunch.engine.plan.model import ActionPlan, Plan, ProcessPlan, Trigger
from tuilaunch.engine.run.events import (
    Event,
    ExitCause,
    Log,
    Output,
    ProcessExited,
    Shutdown,
    Started,
    Stopping,
)
from tuilaunch.engine.run.process.logfiles import LogFile
from tuilaunch.engine.run.process.readers import Running
from tuilaunch.engine.run.supervisor.core import SupervisorCore
from tuilaunch.engine.run.supervisor.ending import Ending
from tuilaunch.engine.run.supervisor.interacting import Interacting
from tuilaunch.engine.run.supervisor.placed import Placing
from tuilaunch.engine.run.supervisor.plan_actions import PlanActions
from tuilaunch.engine.run.supervisor.respawn import MAX_DELAY, Respawner
from tuilaunch.engine.run.supervisor.starting import Starting
from tuilaunch.engine.run.supervisor.stopping import Stopper
from tuilaunch.engine.run.supervisor.triggers import TriggerBook
from tuilaunch.engine.run.vocabulary.requests import Stop

from .terminal_harness import PROGRAMS


def process(pid: str = "talker", **fields: object) -> ProcessPlan:
    values: dict[str, object] = dict(
        id=pid, kind="process", name=pid, namespace="/", package=None, executable="x",
        cmd=["x"], parameters={}, parameter_files=[], generated_parameter_files=[],
        remappings=[], env={}, clear_env=False, cwd=None, respawn=False, respawn_delay=0.0,
        respawn_max_retries=-1, sigterm_timeout=None, sigkill_timeout=None, enabled=True,
        skipped_by=None, trigger=None, origin=None)
    values.update(fields)
    return ProcessPlan(**values)  # type: ignore[arg-type]


def action(aid: str, trigger: Trigger | None) -> ActionPlan:
    return ActionPlan(id=aid, kind="log", target=None, data=None, namespace="/",
                      verbosity="", enabled=True, skipped_by=None, trigger=trigger, origin=None)


def test_respawner_backs_off_while_it_dies_at_once_and_starts_over_after_a_lasting_run():
    respawner = Respawner()
    proc = process(respawn=True, respawn_delay=0.5, respawn_max_retries=-1)
    assert respawner.wants(proc, 1, requested=False)
    assert respawner.wants(proc, 0, requested=False)  # launch respawns a clean exit too
    assert not respawner.wants(proc, -15, requested=True)  # stopped by someone
    delays = [respawner.next_try(proc, started=100.0, now=100.5)[1] for _ in range(12)]
    assert delays[:4] == [0.5, 1.0, 2.0, 4.0]
    assert delays[-1] == MAX_DELAY  # capped: a crash loop waits at most this long
    tries, delay = respawner.next_try(proc, started=100.0, now=200.0)  # it ran 100 s
    assert (tries, delay) == (13, 0.5)


def test_respawner_gives_up_after_the_files_retries():
    respawner = Respawner()
    proc = process(respawn=True, respawn_max_retries=2)
    for _ in range(2):
        assert respawner.wants(proc, 1, requested=False)
        respawner.next_try(proc, started=0.0)
    assert not respawner.wants(proc, 1, requested=False)
    assert respawner.tries(proc.id) == 2


def test_trigger_book_files_handlers_by_event_and_knows_what_can_still_fire():
    book = TriggerBook()
    every_exit = action("a0", Trigger(TriggerOn.EXIT))
    on_output = action("a1", Trigger(TriggerOn.IO, "talker", io="stderr"))
    at_stop = action("a2", Trigger(TriggerOn.SHUTDOWN))
    after_talker = action("a3", Trigger(TriggerOn.EXIT, "talker"))
    filings = [book.file(a) for a in (every_exit, on_output, at_stop, after_talker)]
    assert filings == ["handler", "handler", "handler", "chain"]
    assert book.handlers_of("exit") == [every_exit]
    assert book.output_handlers("talker", "stderr") == [on_output]
    assert book.output_handlers("talker", "stdout") == []
    assert book.on_shutdown == [at_stop] and book.watches_output
    processes = [process()]
    # it waits for the talker's exit: possible while the talker runs, not once it failed
    assert book.action_can_fire(after_talker, {"talker": "running"}, processes)
    assert not book.action_can_fire(after_talker, {"talker": "failed"}, processes)
    book.flag("talker", "exit").set()
    assert book.action_can_fire(after_talker, {"talker": "exited"}, processes)
    assert book.due_in_shutdown([after_talker], {"a3": "pending"}, set())
    book.forget_handlers()
    assert not book.watches_output and book.on_shutdown == []


def test_trigger_book_counts_lifecycle_transitions_for_handlers_that_rerun():
    async def scenario() -> int:
        book = TriggerBook()
        key = ("cam", "state:*|*|active")
        waiter = asyncio.ensure_future(book.next_transition(key, 0))
        await asyncio.sleep(0)
        assert not waiter.done()
        book.state_reached(*key)
        await asyncio.wait_for(waiter, 10)
        book.state_reached(*key)
        return book.transitions(key)

    assert asyncio.run(scenario()) == 2


def test_placing_says_which_side_runs_each_process_and_refuses_to_forward_from_a_share():
    plan = Plan("bringup.py", [], [process("here"), process("there", machine="robot")],
                [action("a0", None)], None, Path("/nonexistent"))  # type: ignore[arg-type]
    launching, share = Placing(), Placing()
    assert launching.place(None, None, plan) == ["there"]  # no coordinator: only hears
    assert launching.runs_here(plan, "here") and not launching.runs_here(plan, "there")
    assert launching.runs_actions()
    assert share.place("robot", None, plan) == ["here", "a0"]  # a share runs no action
    assert share.runs_here(plan, "there") and not share.runs_actions()
    with pytest.raises(LaunchError, match="here runs on the launching side"):
        asyncio.run(share.forward(plan, Stop("here")))  # a typed request (8e86397)


STUBBORN = ("import signal, sys, time\n"
            "signal.signal(signal.SIGINT, signal.SIG_IGN)\n"
            "print('ready', flush=True)\n"
            "time.sleep(60)\n")


@pytest.mark.parametrize("insist", [False, True])
def test_stopper_escalates_a_process_that_ignores_sigint(tmp_path: Path, insist: bool):
    """SIGINT is ignored: SIGTERM follows after the process's own sigterm_timeout, or at
    once when the operator insists; each step is said."""
    said: list[Event] = []
    child = subprocess.Popen([sys.executable, "-c", STUBBORN], stdout=subprocess.PIPE,
                             start_new_session=True)
    try:
        assert child.stdout is not None and child.stdout.readline() == b"ready\n"

        async def scenario() -> float:
            loop = asyncio.get_running_loop()
            stopper = Stopper(60.0, 60.0, said.append, lambda: True)
            proc = process(sigterm_timeout=None if insist else 0.3)
            running = Running(proc, child, LogFile(tmp_path / "x.log", print),
                              time.monotonic(), loop.create_future())

            def poll() -> None:
                if child.poll() is not None:
                    running.exited.set_result(child.returncode)
                else:
                    loop.call_later(0.02, poll)

            poll()
            stopper.began()
            escalation = asyncio.ensure_future(stopper.escalate(running))
            if insist:
                await asyncio.sleep(0.3)
                assert stopper.insist() == "SIGTERM"
            await asyncio.wait_for(escalation, 60)
            return running.exited.result()

        code = asyncio.run(scenario())
    finally:
        if child.poll() is None:
            child.kill()
        child.wait()
    assert code == -signal.SIGTERM
    reasons = [event.reason or "" for event in said]
    name = "talker"  # the process's id, as launch names it in these lines
    assert reasons[0] == f"sending signal 'SIGINT' to process[{name}]"  # no Ctrl+C: said
    if insist:
        assert reasons[1:] == [f"asked again: sending signal 'SIGTERM' to process[{name}]"]
    else:
        assert reasons[1:] == [
            f"process[{name}] failed to terminate '0.3' seconds after receiving "
            "'SIGINT', escalating to 'SIGTERM'",
            f"sending signal 'SIGTERM' to process[{name}]"]


def test_stopper_does_not_count_a_death_by_the_stop_signal_just_before_the_stop():
    stopper = Stopper(5.0, 5.0, lambda event: None, lambda: True)
    crashes = {"raced": -signal.SIGINT, "crashed": -signal.SIGSEGV}
    assert stopper.real_crashes(crashes, {}) == crashes  # no stop: every crash is real
    stopper.began()
    now = time.monotonic()
    assert stopper.real_crashes(crashes, {"raced": now, "crashed": now}) == {
        "crashed": -signal.SIGSEGV}


# --- the behaviours, each over a real core -----------------------------------------------

LAUNCH_HEAD = """import sys
from launch import LaunchDescription
from launch.actions import (ExecuteProcess, LogInfo, RegisterEventHandler, Shutdown,
                            TimerAction)
from launch.event_handlers import OnProcessStart, OnShutdown
def generate_launch_description():
    return LaunchDescription([
"""


def core_of(tmp_path: Path, entities: str) -> tuple[SupervisorCore, list[Event]]:
    """A core over the plan of a launch file holding `entities`, and what it tells."""
    path = tmp_path / "parts_launch.py"
    path.write_text(LAUNCH_HEAD + entities + "    ])\n")
    core = SupervisorCore(resolve(load_file(str(path)), {}, tmp_path / "params"),
                          tmp_path / "log", sigterm_timeout=5, sigkill_timeout=5)
    heard: list[Event] = []
    core.subscribe(heard.append)
    return core, heard


async def until(check: Callable[[], object], what: str, heard: list[Event]) -> None:
    """Waits for `check` on the loop (the parts run on it); the deadline is a hang guard."""
    deadline = time.monotonic() + 60
    while not check():
        assert time.monotonic() < deadline, f"never: {what}; heard {heard}"
        await asyncio.sleep(0.02)


async def closed(core: SupervisorCore) -> None:
    """What a run's end does for the parts made without a Supervisor: its tasks ended, its
    log closed, and the watchdog, which stops whatever of the launch is left, gone."""
    for task in list(core.tasks):
        task.cancel()
    await asyncio.gather(*core.tasks, return_exceptions=True)
    core.launch_log.close()
    core.watchdog.close()
    deadline = time.monotonic() + 30
    while not core.watchdog.finished() and time.monotonic() < deadline:
        await asyncio.sleep(0.02)


def lines_of(heard: list[Event], process: str) -> list[str]:
    return [line for e in heard if isinstance(e, Output) and e.process == process
            for line in e.lines]


def said(heard: list[Event]) -> list[str]:
    return [e.reason or "" for e in heard if isinstance(e, Log)]


async def refused(process_id: str) -> None:
    raise AssertionError(f"nothing here starts or stops a process ({process_id})")


async def test_plan_actions_alone_perform_a_timers_actions_and_hand_its_shutdown_over(
        tmp_path: Path):
    """The timer's LogInfo line is said as launch.user's; its Shutdown goes to the
    supervisor's verb handed in; the Shutdown event then reaches the OnShutdown handler."""
    core, heard = core_of(tmp_path, """
        TimerAction(period=0.2, actions=[LogInfo(msg='tick'), Shutdown(reason='enough')]),
        RegisterEventHandler(OnShutdown(on_shutdown=[LogInfo(msg='bye')])),
""")
    asked: list[str] = []

    async def shutdown(reason: str) -> None:
        asked.append(reason)

    actions = PlanActions(core, start=refused, stop=refused, shutdown=shutdown)
    try:
        for action in core.plan.actions:
            actions.schedule_action(action)
        assert "tick" not in said(heard)  # the timer's, not at once
        await until(lambda: asked, "the shutdown asked for", heard)
        assert asked == ["enough"] and core.shutdown_requested
        tick = next(e for e in heard if isinstance(e, Log) and e.reason == "tick")
        assert tick.data == {"logger": "launch.user"}  # as ros2 launch's LogInfo says it
        assert core.states["log-1"] == core.states["shutdown-2"] == "done"
        assert "bye" not in said(heard)
        await actions.tell_shutdown("enough")
        told = next(e for e in heard if isinstance(e, Shutdown))
        assert told.reason == "enough" and said(heard)[-1] == "bye"
    finally:
        await closed(core)


async def test_starting_alone_starts_a_process_and_follows_it_to_its_end(tmp_path: Path):
    """Its Started event carries the pid the process itself prints; its start runs the
    plan's OnProcessStart handler; its failure is told with its status."""
    core, heard = core_of(tmp_path, """
        RegisterEventHandler(OnProcessStart(on_start=[LogInfo(msg='saw a start')])),
        ExecuteProcess(name='talker', cmd=[sys.executable, '-c',
                       'import os; print(os.getpid(), flush=True); raise SystemExit(3)']),
""")
    actions = PlanActions(core, start=refused, stop=refused, shutdown=refused)
    starting = Starting(core, actions)
    try:
        for action in core.plan.actions:
            actions.schedule_action(action)
        await starting.start("talker-1")
        started = next(e for e in heard if isinstance(e, Started))
        assert started.process == "talker-1" and started.pid is not None
        await until(lambda: core.states["talker-1"] == "failed", "its end", heard)
        assert lines_of(heard, "talker-1") == [str(started.pid)]
        ended = next(e for e in heard if isinstance(e, ProcessExited))
        assert (ended.pid, ended.code, ended.cause) == (started.pid, 3, ExitCause.CRASHED)
        # its record: the end, the crash, and the start it ended (status's command line)
        record = core.records["talker-1"]
        assert (record.exit_code, record.crash_code) == (3, 3) and not core.running
        assert record.started_with is not None and record.started_with.cmd[0] == \
            sys.executable
        assert core.records.having("exit_code") == {"talker-1": 3}
        await until(lambda: "saw a start" in said(heard), "the handler's line", heard)
        # its log file has the line too: "TIME stdout LINE"
        logged = (core.log_dir / "talker-1.log").read_text().split()
        assert logged[1:] == ["stdout", str(started.pid)]
    finally:
        await closed(core)


async def test_ending_alone_shuts_the_launch_down_and_stops_what_runs(tmp_path: Path):
    """The Shutdown event and its handler first, then the process is stopping (its pid
    said), gets SIGINT and ends as asked, not as a crash; then nothing is left to insist on."""
    core, heard = core_of(tmp_path, """
        ExecuteProcess(name='sleeper', cmd=['sleep', '600']),
        RegisterEventHandler(OnShutdown(on_shutdown=[LogInfo(msg='bye')])),
""")
    actions = PlanActions(core, start=refused, stop=refused, shutdown=refused)
    starting = Starting(core, actions)  # only to have something to stop
    ending = Ending(core, actions)
    try:
        for action in core.plan.actions:
            actions.schedule_action(action)
        starting.start_now("sleeper-1")
        pid = core.running["sleeper-1"].process.pid
        await ending.shutdown("test over")
        await until(lambda: core.states["sleeper-1"] == "exited", "its end", heard)
        kinds = [type(e) for e in heard if type(e) in (Shutdown, Stopping, ProcessExited)]
        assert kinds == [Shutdown, Stopping, ProcessExited]
        stopping = next(e for e in heard if isinstance(e, Stopping))
        ended = next(e for e in heard if isinstance(e, ProcessExited))
        assert stopping.pid == ended.pid == pid
        assert ended.code == -signal.SIGINT and ended.cause is ExitCause.ASKED
        assert "bye" in said(heard) and \
            "sending signal 'SIGINT' to process[sleeper-1]" in said(heard)
        assert core.shutting_down and ending.escalate_now() is None
    finally:
        await closed(core)


async def test_interacting_alone_types_a_line_into_a_process_terminal(tmp_path: Path):
    """A bad tool changes nothing; the command it would start with is known before it
    runs; a line typed reaches it and what it answers comes back; ctrl+d ends it."""
    reader = str(PROGRAMS / "line_reader.py")
    core, heard = core_of(tmp_path, f"""
        ExecuteProcess(name='lines', cmd=[sys.executable, {reader!r}], emulate_tty=True),
""")
    starting = Starting(core, PlanActions(core, start=refused, stop=refused,
                                          shutdown=refused))
    hands = Interacting(core, starting)
    try:
        with pytest.raises(LaunchError, match="not running"):
            hands.write_input("lines-1", b"too early\r")
        with pytest.raises(LaunchError):
            hands.restart_options("lines-1", prefix="no-such-tool-here --flag")
        assert not core.records.having("prefix")  # refused: nothing of it kept
        command = hands.command_of("lines-1")
        assert command["command"][-1] == reader and command["terminal"] is True
        starting.start_now("lines-1")
        await until(lambda: "ready" in lines_of(heard, "lines-1"), "ready", heard)
        assert hands.running_process("lines-1") is core.running["lines-1"]
        assert hands.write_input("lines-1", b"hello robot\r") == 0
        await until(lambda: "got: hello robot" in lines_of(heard, "lines-1"), "the answer",
                    heard)
        hands.write_input("lines-1", b"\x04")  # ctrl+d: the end of its input
        await until(lambda: core.states["lines-1"] == "exited", "its end", heard)
        assert "end of input" in lines_of(heard, "lines-1")
    finally:
        await closed(core)
