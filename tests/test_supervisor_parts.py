"""The supervisor's collaborators, each made and driven alone: the Respawner's policy and
backoff, the Stopper's escalation on a real process group, the TriggerBook's handlers and
flags, and Placing's answer to which side runs what."""

from __future__ import annotations

import asyncio
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tuilaunch.engine.errors import LaunchError
from tuilaunch.engine.plan.model import ActionPlan, Plan, ProcessPlan, Trigger
from tuilaunch.engine.run.events import Event
from tuilaunch.engine.run.process.logfiles import LogFile
from tuilaunch.engine.run.process.readers import Running
from tuilaunch.engine.run.supervisor.placed import Placing
from tuilaunch.engine.run.supervisor.respawn import MAX_DELAY, Respawner
from tuilaunch.engine.run.supervisor.stopping import Stopper
from tuilaunch.engine.run.supervisor.triggers import TriggerBook


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
    every_exit = action("a0", Trigger("exit"))
    on_output = action("a1", Trigger("io", "talker", io="stderr"))
    at_stop = action("a2", Trigger("shutdown"))
    after_talker = action("a3", Trigger("exit", "talker"))
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
        asyncio.run(share.forward(plan, "stop", "here"))


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
