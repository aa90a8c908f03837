"""Running plans headless with real processes and real rclpy nodes on an isolated domain."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Awaitable, Callable
from pathlib import Path

import pytest

from tuilaunch.engine.run.process.output import LineSplitter

from ..conftest import EXAMPLES

HEADER = "from simple_launch import SimpleLauncher\n"

STUBBORN = """#!/usr/bin/env python3
import signal, sys, time
signal.signal(signal.SIGINT, signal.SIG_IGN)
signal.signal(signal.SIGTERM, signal.SIG_IGN)
print('stubborn ready', flush=True)
time.sleep(600)
"""


def stubborn_script(folder: Path) -> Path:
    """STUBBORN as an executable in `folder`: a process that ignores SIGINT and SIGTERM."""
    script = folder / "stubborn"
    script.write_text(STUBBORN)
    script.chmod(0o755)
    return script


def start_headless(*args: str, log_dir: Path) -> subprocess.Popen[str]:
    env = {**os.environ, "ROS_LOG_DIR": str(log_dir)}
    return subprocess.Popen([sys.executable, "-m", "tuilaunch", *args, "--headless"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=env, start_new_session=True)


def read_until(proc: subprocess.Popen[str], *needles: str, limit: float = 60) -> str:
    """Output lines until every needle has been seen (or the limit, a hang guard only)."""
    seen = ""
    deadline = time.monotonic() + limit
    assert proc.stdout is not None
    while not all(n in seen for n in needles):
        if time.monotonic() > deadline:
            raise AssertionError(f"never saw {needles}:\n{seen}")
        line = proc.stdout.readline()
        if not line:
            raise AssertionError(f"output ended before {needles}:\n{seen}")
        seen += line
    return seen


def pids_of(log_dir: Path) -> list[int]:
    text = (next(log_dir.glob("*-tuilaunch-*")) / "launch.log").read_text()
    return [int(word[4:]) for line in text.splitlines() if " started " in line
            for word in line.split() if word.startswith("pid=")]


def alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().split()[2] != "Z"
    except FileNotFoundError:
        return False


def wait_gone(pids: list[int], limit: float = 30) -> list[int]:
    deadline = time.monotonic() + limit
    while time.monotonic() < deadline and any(alive(p) for p in pids):
        time.sleep(0.1)
    return [p for p in pids if alive(p)]


@pytest.fixture
def kill_leftovers():
    started: list[subprocess.Popen[str]] = []
    yield started
    for proc in started:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def test_bringup_service_call_and_parameter_change_take_effect(tmp_path, kill_leftovers):
    proc = start_headless(str(EXAMPLES / "bringup.py"), "robot:=r8", "mode:=dock",
                          log_dir=tmp_path)
    kill_leftovers.append(proc)
    seen = read_until(proc, "[r8.service_server]: reset called (1 so far)",
                      "/r8/reset response: {'success': True, 'message': 'reset #1'}",
                      "[r8.control.configurable]: parameter mode set to 'dock'",
                      "/r8/control/configurable set mode='dock'")
    # the call waits for the server the group is triggered by; the parameters wait for
    # the node that starts a second after the talker
    assert seen.index("[INFO] [service_server-4]: process started") < seen.index(
        "reset called")
    os.killpg(proc.pid, signal.SIGINT)
    assert proc.wait(timeout=60) == 0


def test_event_callbacks_and_shutdown_actions_run(write, tmp_path, kill_leftovers):
    path = write(HEADER + """
from launch.actions import LogInfo, ExecuteProcess, RegisterEventHandler
from launch.event_handlers import OnProcessExit
from launch.substitutions import LocalSubstitution
from simple_launch.events import When, OnProcessIO, OnExecutionComplete, OnShutdown
def generate_launch_description():
    sl = SimpleLauncher()
    speaker = sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo one; echo two'],
                                           name='speaker'))
    with sl.group(when=When(speaker, OnProcessIO, io='stdout')):
        sl.add_action(lambda event: LogInfo(msg='heard ' + event.text.decode().strip()))
    sl.add_action(RegisterEventHandler(OnProcessExit(target_action=speaker,
        on_exit=lambda event, context: [LogInfo(msg=f'speaker exited')])))
    with sl.group(when=When(speaker, OnExecutionComplete)):
        sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo after; sleep 600'], name='after'))
    with sl.group(when=When(event=OnShutdown)):
        sl.log_info(['stopping: ', LocalSubstitution('event.reason')])
    return sl.launch_description()
""")
    proc = start_headless(str(path), log_dir=tmp_path)
    kill_leftovers.append(proc)
    seen = read_until(proc, "heard one", "heard two", "speaker exited", "[after-2] after")
    os.killpg(proc.pid, signal.SIGTERM)
    rest = proc.communicate(timeout=60)[0]
    assert "stopping: received SIGTERM" in rest
    assert seen.index("[INFO] [speaker-1]: process has finished") < seen.index(
        "[INFO] [after-2]: process started")


def test_bringup_runs_real_nodes_with_their_namespaces_and_parameters(tmp_path, kill_leftovers):
    proc = start_headless(str(EXAMPLES / "bringup.py"), "robot:=r7", "rate:=20",
                          "services:=false", log_dir=tmp_path)
    kill_leftovers.append(proc)
    seen = read_until(proc, '[talker-1] STARTUP {"node": "/r7/talker"',
                      '[listener-2] [INFO]', 'I heard: "r7 says hi',
                      '[monitor-5] STARTUP {"node": "/r7/monitor"',
                      '"chatter": "/r7/chatter"', "[configurable-3] STARTUP")
    assert '"rate": 20' in seen and '"message": "r7 says hi"' in seen
    # the event-triggered group starts after the talker it waits for
    assert seen.index("[INFO] [talker-1]: process started") < seen.index(
        "[INFO] [configurable-3]: process started")
    assert "service_server" not in seen
    os.killpg(proc.pid, signal.SIGINT)
    rest = proc.communicate(timeout=60)[0]
    # ros2 launch's line for Ctrl+C, and no reason line (it logs none)
    assert "[WARNING] [launch]: user interrupted with ctrl-c (SIGINT)" in rest
    assert "shutdown (" not in rest
    pids = pids_of(tmp_path)
    assert len(pids) == 4 and wait_gone(pids) == []
    logs = next(tmp_path.glob("*-tuilaunch-*"))
    assert 'I heard: "r7 says hi' in (logs / "listener-2.log").read_text()


@pytest.mark.parametrize("how", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP,
                                 signal.SIGKILL])
def test_no_process_outlives_tuilaunch(write, tmp_path, kill_leftovers, how):
    script = stubborn_script(tmp_path)
    path = write(HEADER + f"""
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    # launch's own escalation, shorter than its 5 s defaults: SIGTERM 1 s after the
    # ignored SIGINT, SIGKILL 1 s after the ignored SIGTERM
    sl.add_action(ExecuteProcess(cmd=['{script}'], name='stubborn', sigterm_timeout='1',
                                 sigkill_timeout='1'))
    sl.node('tuilaunch_demos', 'no_such_exe')
    sl.node('tuilaunch_demos', 'listener')
    return sl.launch_description()
""")
    logs = tmp_path / "logs"
    proc = start_headless(str(path), log_dir=logs)
    kill_leftovers.append(proc)
    seen = read_until(proc, "[stubborn-1] stubborn ready", "[listener-3] STARTUP",
                      "[ERROR] [no_such_exe-2]: failed to start: executable 'no_such_exe'")
    assert "available: component_container, configurable" in seen
    pids = pids_of(logs)
    os.kill(proc.pid, how)
    proc.wait(timeout=60)
    # the stubborn process ignores SIGINT and SIGTERM: only SIGKILL (or pdeathsig) ends it
    assert wait_gone(pids) == []


def test_respawn_restarts_a_crashing_process_a_bounded_number_of_times(write, tmp_path,
                                                                       kill_leftovers):
    path = write(HEADER + """
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo crash; exit 3'], name='crasher',
                                 respawn=True, respawn_delay=0.1, respawn_max_retries=2))
    sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo done; exit 0'], name='clean',
                                 respawn=True, respawn_delay=0.1, respawn_max_retries=1))
    return sl.launch_description()
""")
    proc = start_headless(str(path), log_dir=tmp_path)
    kill_leftovers.append(proc)
    out = proc.communicate(timeout=60)[0]
    assert out.count("[crasher-1] crash") == 3  # first run and two respawns
    assert out.count("[crasher-1]: respawning") == 2, out
    assert "[ERROR] [crasher-1]: respawn gives up: it failed 3 times (respawn_max_retries=2)" \
        in out
    # a clean exit is respawned too, as launch's ExecuteLocal does whatever the status
    assert out.count("[clean-2] done") == 2 and out.count("[clean-2]: respawning") == 1
    assert "[clean-2]: respawn gives up: it ended 2 times (respawn_max_retries=1)" in out
    assert proc.returncode == 1  # the crash is reported in the exit status


def test_respawn_backs_off_while_it_dies_at_once_and_starts_over_after_a_lasting_run(
        write, tmp_path, kill_leftovers):
    runs = tmp_path / "runs"
    script = ("n=$(cat RUNS 2>/dev/null || echo 0); n=$((n+1)); echo $n > RUNS; echo run $n; "
              "if [ $n -eq 3 ]; then sleep 2.5; fi; exit 3").replace("RUNS", str(runs))
    path = write(HEADER + f"""
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(cmd=['sh', '-c', {script!r}], name='driver',
                                 respawn=True, respawn_delay=0.1, respawn_max_retries=4))
    return sl.launch_description()
""")
    proc = start_headless(str(path), log_dir=tmp_path / "log")
    kill_leftovers.append(proc)
    out = proc.communicate(timeout=60)[0]
    delays = [line.split("try ", 1)[1] for line in out.splitlines() if "respawning (" in line]
    # runs 1 and 2 die at once (the delay doubles), run 3 lasts (it starts over), 4 at once
    assert delays == ["1 in 0.1 s)", "2 in 0.2 s)", "3 in 0.1 s)", "4 in 0.1 s)"], out



async def test_a_stop_while_it_waits_to_respawn_calls_the_respawn_off(write, tmp_path):
    """Stopped between two runs (a group stopped while one of its nodes waits out its
    respawn delay), a process does not come back, and the launch then ends as nothing runs;
    restarted between two runs, it runs once, and stays running when the wait ends."""
    import asyncio

    from tuilaunch.engine import load_file, resolve
    from tuilaunch.engine.run.supervisor.supervisor import Event, Supervisor

    path = write(HEADER + """
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    for name in ('stopped', 'restarted'):
        sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo up; exec sleep 600'], name=name,
                                     respawn=True, respawn_delay=600.0))
    return sl.launch_description()
""")
    plan = resolve(load_file(str(path)), {}, tmp_path / "params")
    supervisor = Supervisor(plan, tmp_path / "log", sigterm_timeout=3)
    events: list[Event] = []
    supervisor.subscribe(events.append)
    run = asyncio.ensure_future(supervisor.run())

    async def until(condition, what: str) -> None:  # type: ignore[no-untyped-def]
        deadline = asyncio.get_running_loop().time() + 60
        while not condition():
            assert asyncio.get_running_loop().time() < deadline, (what, supervisor.states)
            await asyncio.sleep(0.02)

    def starts(process: str) -> int:
        return [e.kind for e in events if e.process == process].count("started")

    try:
        await until(lambda: len(supervisor.running) == 2, "both started")
        for running in list(supervisor.running.values()):
            os.kill(running.process.pid, signal.SIGKILL)  # a crash each: both respawn
        await until(lambda: set(supervisor.states.values()) == {"respawning"}, "respawning")
        await supervisor.restart("restarted-2")
        await supervisor.stop("stopped-1")
        # the restarted one's respawn wait ended, and left it running, started once more
        await until(lambda: not supervisor.respawn_waits and not supervisor.busy, "settled")
        assert supervisor.states["restarted-2"] == "running" and starts("restarted-2") == 2
        assert supervisor.states["stopped-1"] == "exited" and starts("stopped-1") == 1
        assert any(e.kind == "log" and e.process == "stopped-1"
                   and "respawn called off" in (e.reason or "") for e in events)
        await supervisor.stop("restarted-2")
        # nothing runs and no respawn waits: the run ends, the 600 s no longer hold it (its
        # status 1 says the crashes)
        assert await asyncio.wait_for(run, 60) == 1
    finally:
        if not run.done():
            await supervisor.shutdown("test over")
            await asyncio.wait_for(run, 30)

def test_line_splitter_handles_partial_lines_progress_and_bad_bytes():
    splitter = LineSplitter()
    assert splitter.feed(b"hel") == []
    assert splitter.feed(b"lo\nwor") == ["hello"]
    assert splitter.feed(b"ld\r\n10%\r50%\r100%\n\xff\xfeok\n") == [
        "world", "100%", "\ufffd\ufffdok"]
    assert splitter.feed(b"x" * 200_000) == []  # a long line is kept whole, not cut at 64 KB
    assert splitter.flush() == ["x" * 200_000] and splitter.flush() == []


def test_display_buffer_drops_oldest_lines_and_counts_them_but_never_other_events():
    from tuilaunch.engine.run.event_buffer import EventBuffer
    from tuilaunch.engine.run.events import Event, Output, Started

    buffer = EventBuffer(max_lines=1000)
    buffer(Started("flood-1", pid=1))
    for start in range(0, 100_000, 100):
        buffer(Output("flood-1", stream="stdout",
                      lines=[str(n) for n in range(start, start + 100)]))
    buffer(Event("exited", "flood-1", code=0))
    events = buffer.drain()
    assert [e.kind for e in events if e.kind != "output"] == ["dropped", "started", "exited"]
    shown = [line for e in events if e.kind == "output" for line in e.lines]
    assert shown == [str(n) for n in range(99_000, 100_000)]  # the newest lines, in order
    assert events[0].code == 99_000 and buffer.total_dropped == 99_000
    assert buffer.drain() == []


def test_flood_loses_no_line_in_the_log_file(write, tmp_path, kill_leftovers):
    count = 200_000
    path = write(HEADER + f"""
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    for i in range(2):
        sl.add_action(ExecuteProcess(cmd=['seq', '1', '{count}'], name=f'flood{{i}}'))
    return sl.launch_description()
""")
    proc = start_headless(str(path), log_dir=tmp_path)
    kill_leftovers.append(proc)
    out = proc.communicate(timeout=120)[0]
    assert proc.returncode == 0
    folder = next(tmp_path.glob("*-tuilaunch-*"))
    for name in ("flood0-1", "flood1-2"):
        numbers = [line.split(" ", 2)[2] for line in
                   (folder / f"{name}.log").read_text().splitlines()]
        assert numbers == [str(n) for n in range(1, count + 1)]
    # headless shows no line past 1 MB waiting for a reader slower than the flood (this
    # test's, on a busy machine) and says how many: shown + said is every line
    skipped = sum(int(n) for n in re.findall(r"(\d+) output lines not shown", out))
    assert out.count("[flood0-1] ") + out.count("[flood1-2] ") + skipped == 2 * count


async def loop_until(check: Callable[[], object], said: Callable[[], object],
                     limit: float = 60) -> None:
    """On the supervisor's loop: waits until `check` holds; past `limit`, fails with `said`."""
    import asyncio

    deadline = asyncio.get_running_loop().time() + limit
    while not check():
        assert asyncio.get_running_loop().time() < deadline, said()
        await asyncio.sleep(0.05)


def test_stop_restart_and_start_one_process_while_the_others_run(write, tmp_path):
    import asyncio

    from tuilaunch.engine import load_file, resolve
    from tuilaunch.engine.run.supervisor.supervisor import Supervisor

    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher()
    sl.node('tuilaunch_demos', 'listener', name='ear', remappings={'chatter': '/news'})
    sl.node('tuilaunch_demos', 'talker', name='mouth', parameters={'rate': 20.0})
    return sl.launch_description()
""")
    plan = resolve(load_file(str(path)), {}, params_dir=tmp_path / "params")
    supervisor = Supervisor(plan, tmp_path / "log", sigterm_timeout=5)
    events: list = []
    supervisor.subscribe(events.append)

    def output_of(process: str) -> str:
        return "".join(line + "\n" for e in events if e.kind == "output" and e.process == process
                       for line in e.lines)

    def until(check) -> Awaitable[None]:
        return loop_until(check, lambda: [e.kind for e in events])

    async def scenario() -> int:
        run = asyncio.ensure_future(supervisor.run(keep_alive=True))
        await until(lambda: '"chatter": "/news"' in output_of("ear-1"))
        await until(lambda: "Publishing" in output_of("mouth-2"))
        await supervisor.stop("mouth-2")
        assert supervisor.states == {"ear-1": "running", "mouth-2": "exited"}
        await supervisor.restart("ear-1")
        await until(lambda: output_of("ear-1").count("STARTUP") == 2)
        await supervisor.start("mouth-2")
        await until(lambda: output_of("mouth-2").count("STARTUP") == 2)
        await supervisor.stop("ear-1")
        await supervisor.stop("mouth-2")
        await asyncio.sleep(0.2)
        assert not run.done()  # with every process stopped, the operator can still start one
        await supervisor.shutdown("test done")
        return await run

    status = asyncio.run(scenario())
    starts = [e.process for e in events if e.kind == "started"]
    assert starts == ["ear-1", "mouth-2", "ear-1", "mouth-2"]
    assert [e.process for e in events if e.kind == "exited"] == [
        "mouth-2", "ear-1", "ear-1", "mouth-2"]
    assert output_of("ear-1").count("STARTUP") == 2
    assert status == 0 and not (tmp_path / "params").exists()  # parameter files are removed


def test_a_restart_starts_it_again_when_a_child_holds_its_output_past_its_exit(write,
                                                                            tmp_path):
    """A program whose SIGINT handler leaves a child holding its terminal for a moment: it
    is reaped before its output ends. The restart (and a relaunch, which stops the same
    way) must start it again once its end is told, not find it still running and leave it
    stopped (seen in CI: `g` in the TUI restarted a node under a tool that then never ran)."""
    import asyncio

    from tuilaunch.engine import load_file, resolve
    from tuilaunch.engine.run.supervisor.supervisor import Supervisor

    path = write(HEADER + """from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(name='holder', output='screen', cmd=['sh', '-c',
        'trap "sleep 0.5 & exit 0" INT; echo ready; while true; do sleep 0.1; done']))
    sl.add_action(ExecuteProcess(name='quitter', output='screen', cmd=['sh', '-c',
        'echo bye; sleep 0.5 & exit 0']))
    return sl.launch_description()
""")
    supervisor = Supervisor(resolve(load_file(str(path)), {}), tmp_path / "log")
    events: list = []
    supervisor.subscribe(events.append)

    def reaped(process: str) -> bool:
        running = supervisor.running.get(process)
        return running is not None and running.exited.done()

    def readies() -> int:
        return sum(line == "ready" for e in events if e.kind == "output" for line in e.lines)

    def until(check) -> Awaitable[None]:
        return loop_until(check, lambda: [e.kind for e in events])

    async def scenario() -> int:
        run = asyncio.ensure_future(supervisor.run(keep_alive=True))
        # started by the operator while its output is still held after it exited (or, on
        # a slow machine, once it is over)
        await until(lambda: reaped("quitter-2") or supervisor.states["quitter-2"] == "exited")
        await supervisor.start("quitter-2")
        await until(lambda: readies() == 1)
        await supervisor.restart("holder-1")
        assert supervisor.states["holder-1"] == "running"
        await until(lambda: readies() == 2)
        await until(lambda: sum(e.kind == "started" and e.process == "quitter-2"
                                for e in events) == 2)
        await supervisor.shutdown("test done")
        return await run

    asyncio.run(scenario())
    # each end is told before the new start, as a log reader expects
    for process in ("holder-1", "quitter-2"):
        assert [e.kind for e in events if e.kind in ("started", "exited")
                and e.process == process] == ["started", "exited", "started", "exited"]


def test_log_file_holds_each_line_while_the_process_still_runs(write, tmp_path, kill_leftovers):
    path = write(HEADER + """
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo first line; sleep 600'], name='slow'))
    return sl.launch_description()
""")
    proc = start_headless(str(path), log_dir=tmp_path)
    kill_leftovers.append(proc)
    read_until(proc, "[slow-1] first line")
    log = next(tmp_path.glob("*-tuilaunch-*")) / "slow-1.log"
    assert log.read_text().endswith(" stdout first line\n")  # not held in a buffer
    os.killpg(proc.pid, signal.SIGINT)
    proc.wait(timeout=60)


def test_line_splitter_blocks_keep_bytes_and_cut_endless_lines():
    from tuilaunch.engine.run.process.output import MAX_LINE, screen_lines

    splitter = LineSplitter()
    assert splitter.feed_block(b"par") == b""
    # a line rewritten with \r is kept in its last state; a terminal's \r\n stays
    assert splitter.feed_block(b"tial\nnext\r50%\r100%\nx") == b"partial\n100%\n"
    assert screen_lines(b"partial\nnext\r50%\r100%\n") == ["partial", "100%"]
    assert screen_lines(b"a\x00b\n\xff\n") == ["ab", "\ufffd"]
    block = splitter.feed_block(b"y" * (2 * MAX_LINE + 5))
    assert block == b"x" + b"y" * (MAX_LINE - 1) + b"\n" + b"y" * MAX_LINE + b"\n"
    assert splitter.flush_block() == b"y" * 6 + b"\n" and splitter.flush_block() == b""
    assert splitter.feed_block(b"x\r\nok\r") == b"x\r\n" and splitter.tail == b"ok\r"
    assert splitter.feed_block(b"\n") == b"ok\r\n"
    # an endless progress line is kept in its last state, never cut into pieces
    assert splitter.feed_block(b"\r".join(b"%d%%" % i for i in range(50000))) == b""
    assert splitter.tail == b"49999%"
