"""The supervisor under faults, each reproduced with real processes: a consumer that fails,
a full disk, a dead terminal, daemons holding pipes, signals during bring-up, tuilaunch
killed outright, and what an operator sees while a launch stops."""

from __future__ import annotations

import asyncio
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import pytest

from tuilaunch.engine import load_file, resolve
from tuilaunch.engine.run.supervisor.supervisor import Event, Supervisor

from ..conftest import run_cli
from .test_supervisor import (
    HEADER,
    alive,
    pids_of,
    read_until,
    start_headless,
    stubborn_script,
    wait_gone,
)

PROCESS_HEADER = HEADER + "from launch.actions import ExecuteProcess\n"


def tagged(tag: str) -> list[int]:
    """Live processes whose command line holds the tag (what a test started, by any path)."""
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                cmdline = Path(f"/proc/{entry}/cmdline").read_bytes()
            except OSError:
                continue
            if tag.encode() in cmdline and alive(int(entry)):
                found.append(int(entry))
    return found


@pytest.fixture
def launches(tmp_path):
    """Every tuilaunch a test starts, and every process carrying the test's tag, ends with it.

    The tag is also a `sleep` under another name: `{tag} 600` sleeps, and says whose it is."""
    started: list[subprocess.Popen[str]] = []
    tag = f"tl{uuid.uuid4().hex[:10]}"
    (tmp_path / tag).symlink_to(shutil.which("sleep") or "/bin/sleep")
    os.environ["PATH"] = f"{tmp_path}{os.pathsep}{os.environ['PATH']}"
    yield started, tag
    os.environ["PATH"] = os.environ["PATH"].split(os.pathsep, 1)[1]
    for proc in started:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    for pid in tagged(tag):
        os.kill(pid, signal.SIGKILL)


def launch_file(write, body: str) -> Path:
    lines = "\n".join("    " + line for line in body.strip().splitlines())
    return write(PROCESS_HEADER + "def generate_launch_description():\n    sl = SimpleLauncher()\n"
                 + lines + "\n    return sl.launch_description()\n")


def log_folder(root: Path) -> Path:
    return next(root.glob("*-tuilaunch-*"))


# --- a failing consumer never stops a node's pipe nor a shutdown ------------------------------


def test_closed_stdout_loses_no_line_and_the_launch_runs_to_its_end(write, tmp_path, launches):
    started, _ = launches
    count = 200_000
    path = launch_file(write, f"sl.add_action(ExecuteProcess(cmd=['seq', '1', '{count}'], "
                              "name='flood'))")
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path)}
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                            start_new_session=True)
    started.append(proc)
    assert proc.stdout is not None and proc.stderr is not None
    head = [proc.stdout.readline() for _ in range(3)]  # `| head -3`
    proc.stdout.close()
    assert "All log files" in head[0]
    assert proc.wait(timeout=120) == 0
    errors = proc.stderr.read()
    assert errors.count("cannot write to stdout (Broken pipe)") == 1, errors
    assert "Traceback" not in errors
    logged = (log_folder(tmp_path) / "flood-1.log").read_bytes().splitlines()
    assert [line.split(b" ", 2)[2] for line in logged] == [
        str(n).encode() for n in range(1, count + 1)]


def test_a_reader_that_stops_reading_freezes_no_node_and_ctrl_c_still_stops(write, tmp_path,
                                                                            launches):
    """A terminal paused with Ctrl+S, an ssh link slower than the output, `| less` left
    open: the nodes run on at their own pace, Ctrl+C stops them at once, and once the reader
    reads again the screen says how many lines it was not shown (the log has them all)."""
    started, _ = launches
    count = 300_000
    half = count // 2  # the second half comes once stdout has stalled: it is skipped
    path = launch_file(write, f"""
sl.add_action(ExecuteProcess(name='flood', cmd=[
    'sh', '-c', 'seq 1 {half}; sleep 0.5; seq {half + 1} {count}']))
sl.add_action(ExecuteProcess(cmd=['sleep', '600'], name='idle'))""")
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path)}
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env,
                            start_new_session=True)
    started.append(proc)
    logged = 0
    deadline = time.monotonic() + 120
    while logged < count and time.monotonic() < deadline:  # nobody reads stdout meanwhile
        time.sleep(0.2)
        logs = list(tmp_path.glob("*-tuilaunch-*/flood-1.log"))
        logged = logs[0].read_bytes().count(b"\n") if logs else 0
    assert logged == count  # it froze at the pipe's 64 KB before
    shown: list[bytes] = []
    assert proc.stdout is not None
    reader = threading.Thread(target=lambda: shown.append(proc.stdout.read()))  # type: ignore
    reader.start()
    os.killpg(proc.pid, signal.SIGINT)
    assert proc.wait(timeout=60) == 0
    reader.join(timeout=30)
    out = shown[0].decode()
    skipped = sum(int(n) for n in re.findall(r"(\d+) output lines not shown", out))
    assert skipped > 0 and "they are in the log files below" in out
    assert out.count("[flood-1] ") + skipped == count
    assert re.search(r"\[INFO\] \[idle-2\]: process stopped \[pid \d+, killed by SIGINT\]", out)


@pytest.mark.parametrize("closed", [(1,), (0, 1), (2,)], ids=["stdout", "stdin+stdout",
                                                              "stderr"])
def test_a_launch_started_with_closed_std_fds_runs_and_logs_every_line(write, tmp_path,
                                                                       launches, closed):
    """`tuilaunch f.py --headless >&-` (a cron line, a service unit): no traceback, the nodes
    run, and the log files hold what they printed, not what tuilaunch meant for the terminal."""
    started, _ = launches
    path = launch_file(write, "sl.add_action(ExecuteProcess(cmd=['seq', '1', '500'], "
                              "name='counter'))")
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path)}
    errors = tmp_path / "errors.txt"
    redirections = " ".join(f"{fd}>&-" if fd else "<&-" for fd in closed)
    if 2 not in closed:
        redirections += f" 2>{errors}"
    proc = subprocess.Popen(["sh", "-c", f'exec "$0" -m tuilaunch "$1" --headless {redirections}',
                             sys.executable, str(path)], env=env, start_new_session=True)
    started.append(proc)
    assert proc.wait(timeout=60) == 0
    logged = (log_folder(tmp_path) / "counter-1.log").read_bytes().splitlines()
    assert [line.split(b" ", 2)[2] for line in logged] == [
        str(n).encode() for n in range(1, 501)]
    launch_log = (log_folder(tmp_path) / "launch.log").read_text()
    assert "exited counter-1" in launch_log and "All log files" not in launch_log
    if 2 not in closed:
        said = errors.read_text()
        assert "Traceback" not in said
        assert said.count("stdout is closed") == (1 if 1 in closed else 0), said


def test_a_full_disk_is_said_once_and_neither_the_node_nor_the_stop_hangs(write, tmp_path,
                                                                         launches):
    started, _ = launches
    disk = tmp_path / "disk"
    disk.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(disk)],
                             capture_output=True)
    if mounted.returncode != 0:
        pytest.skip("a small tmpfs needs root: " + mounted.stderr.decode().strip())
    try:
        count = 100_000
        path = launch_file(write, f"""
sl.add_action(ExecuteProcess(cmd=['seq', '1', '{count}'], name='flood'))
sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'sleep 1; echo still here; sleep 600'],
                             name='quiet'))""")
        proc = start_headless(str(path), log_dir=disk)
        started.append(proc)
        lines: list[str] = []
        # the flood's end, said by tuilaunch (its own lines are never skipped: a slow reader
        # on a busy machine may not be shown the flood's last line itself), and the quiet node
        wanted = {"[INFO] [flood-1]: process has finished cleanly", "[quiet-2] still here"}
        deadline = time.monotonic() + 120
        assert proc.stdout is not None
        while wanted and time.monotonic() < deadline:
            lines.append(proc.stdout.readline())
            wanted = {w for w in wanted if not lines[-1].startswith(w)}
            assert lines[-1], "".join(lines[-20:])
        assert not wanted
        os.killpg(proc.pid, signal.SIGINT)
        rest = proc.communicate(timeout=60)[0]
        assert proc.returncode == 0
        everything = "".join(lines) + rest
        assert "No space left on device" in everything
        # one message per file that filled, not one per line
        assert everything.count("cannot write log file") <= 3
        assert f"{log_folder(disk) / 'flood-1.log'}" in everything
        # the screen still got every line, or says how many a slow reader was not shown
        skipped = sum(int(n) for n in re.findall(r"(\d+) output lines not shown", everything))
        assert everything.count("[flood-1] ") + skipped == count
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=False)


def test_a_consumer_that_raises_never_stops_reading_nor_the_shutdown(write, tmp_path):
    path = launch_file(write, """
sl.add_action(ExecuteProcess(cmd=['seq', '1', '50000'], name='flood'))
sl.add_action(ExecuteProcess(cmd=['sleep', '600'], name='sleeper'))""")
    plan = resolve(load_file(str(path)), {}, params_dir=tmp_path / "params")
    supervisor = Supervisor(plan, tmp_path / "log")
    events: list[Event] = []

    def broken(event: Event) -> None:
        raise OSError(5, "Input/output error")

    supervisor.subscribe(broken)
    supervisor.subscribe(events.append)

    async def scenario() -> int:
        run = asyncio.ensure_future(supervisor.run())
        deadline = time.monotonic() + 60
        while not any(e.kind == "exited" and e.process == "flood-1" for e in events):
            assert time.monotonic() < deadline
            await asyncio.sleep(0.05)
        await supervisor.shutdown("test done")
        return await run

    assert asyncio.run(scenario()) == 0
    lines = [line for e in events if e.kind == "output" for line in e.lines]
    assert lines[-1] == "50000" and len(lines) == 50000
    assert len((tmp_path / "log" / "flood-1.log").read_bytes().splitlines()) == 50000
    assert [e.process for e in events if e.kind == "exited"] == ["flood-1", "sleeper-2"]


def test_sighup_with_the_terminal_gone_stops_every_node(write, tmp_path, launches):
    started, tag = launches
    script = stubborn_script(tmp_path)
    path = launch_file(write, f"""
sl.add_action(ExecuteProcess(cmd=['{tag}', '600'], name='sleeper'))
sl.add_action(ExecuteProcess(cmd=['{script}', '{tag}'], name='stubborn',
                             sigterm_timeout='0.5', sigkill_timeout='0.5'))""")
    master, slave = os.openpty()
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path)}
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                            stdin=slave, stdout=slave, stderr=slave, env=env,
                            start_new_session=True, text=True)
    started.append(proc)
    os.close(slave)
    seen = b""
    deadline = time.monotonic() + 60
    while b"stubborn ready" not in seen:
        assert time.monotonic() < deadline, seen
        seen += os.read(master, 4096)
    os.close(master)  # the ssh link drops: every later write to the terminal fails
    os.kill(proc.pid, signal.SIGHUP)
    assert proc.wait(timeout=60) == 0
    assert wait_gone(tagged(tag)) == []
    text = (log_folder(tmp_path) / "launch.log").read_text()
    assert "shutdown  reason=received SIGHUP" in text
    assert "exited stubborn-2" in text and "killed by SIGKILL" in text


# --- exits are reported at once; nothing is left untracked -------------------------------------


def test_a_daemon_holding_the_pipe_does_not_delay_the_exit_and_is_stopped_at_the_end(
        write, tmp_path, launches):
    started, tag = launches
    path = launch_file(write, f"""
from launch.actions import LogInfo, RegisterEventHandler
from launch.event_handlers import OnProcessExit
parent = sl.add_action(ExecuteProcess(cmd=['sh', '-c',
    'setsid sh -c "echo daemon \\\\$\\\\$; exec {tag} 600" & sleep 0.2; echo parent done'],
    name='parent'))
sl.add_action(RegisterEventHandler(OnProcessExit(target_action=parent,
    on_exit=lambda event, context: [LogInfo(msg='saw the exit')])))
sl.add_action(ExecuteProcess(cmd=['{tag}', '600'], name='keeper'))""")
    proc = start_headless(str(path), log_dir=tmp_path)
    started.append(proc)
    seen = read_until(proc, "saw the exit", limit=30)
    daemon = int(seen.split("[parent-1] daemon ")[1].split()[0])
    assert "[INFO] [parent-1]: process has finished cleanly [pid" in seen
    # the launch runs on (keeper): the exit was reported while the daemon still held the pipe
    assert alive(daemon)
    os.killpg(proc.pid, signal.SIGINT)
    assert proc.wait(timeout=60) == 0
    assert wait_gone([daemon]) == []  # and the launch did not leave it behind


@pytest.mark.parametrize("after", [1, 40])
def test_sigint_during_bringup_of_100_processes_signals_every_one(write, tmp_path, launches,
                                                                  after):
    started, tag = launches
    path = launch_file(write, f"""
for i in range(100):
    sl.add_action(ExecuteProcess(cmd=['{tag}', '600'], name=f's{{i}}'))""")
    proc = start_headless(str(path), log_dir=tmp_path)
    started.append(proc)
    read_until(proc, *[f"[s{i}-{i + 1}]: process started" for i in range(after)])
    os.killpg(proc.pid, signal.SIGINT)
    rest = proc.communicate(timeout=60)[0]
    assert proc.returncode == 0, rest  # sleep dies of the SIGINT we sent: a clean stop
    pids = pids_of(tmp_path)
    assert wait_gone(pids) == [] and tagged(tag) == []
    text = (log_folder(tmp_path) / "launch.log").read_text()
    exits = [line for line in text.splitlines() if " exited " in line]
    assert len(exits) == len(pids)
    assert all("killed by SIGINT" in line for line in exits), exits


def test_a_log_file_that_cannot_be_opened_starts_no_process(write, tmp_path):
    marker = tmp_path / "ran"
    path = launch_file(write, f"""
sl.add_action(ExecuteProcess(cmd=['touch', '{marker}'], name='blocked'))
sl.add_action(ExecuteProcess(cmd=['true'], name='fine'))
sl.add_action(ExecuteProcess(cmd=['echo', 'a' + chr(0) + 'b'], name='nul'))""")
    plan = resolve(load_file(str(path)), {}, params_dir=tmp_path / "params")
    (tmp_path / "log" / "blocked-1.log").mkdir(parents=True)  # the log file cannot be opened
    supervisor = Supervisor(plan, tmp_path / "log")
    events: list[Event] = []
    supervisor.subscribe(events.append)
    assert asyncio.run(supervisor.run()) == 1
    failed = [e for e in events if e.kind == "failed"]
    assert [e.process for e in failed] == ["blocked-1", "nul-3"]
    assert "cannot open its log file" in (failed[0].reason or "")
    assert "Is a directory" in (failed[0].reason or "")
    assert "embedded null byte" in (failed[1].reason or "")  # said, not a hang
    assert not marker.exists()
    assert [e.process for e in events if e.kind == "exited"] == ["fine-2"]


def test_the_open_file_limit_fails_some_processes_and_leaves_none_untracked(write, tmp_path,
                                                                          launches):
    started, tag = launches
    path = launch_file(write, f"""
for i in range(60):
    sl.add_action(ExecuteProcess(cmd=['{tag}', '600'], name=f's{{i}}'))""")
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path)}
    import resource

    def low_limit() -> None:
        resource.setrlimit(resource.RLIMIT_NOFILE, (120, 120))

    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=env, start_new_session=True, preexec_fn=low_limit)
    started.append(proc)
    seen = read_until(proc, "Too many open files", "[s59-60]")
    os.killpg(proc.pid, signal.SIGINT)
    rest = proc.communicate(timeout=60)[0]
    assert proc.returncode == 1  # a process that could not start is a failure
    assert "Traceback" not in seen + rest and "never retrieved" not in seen + rest
    running = (seen + rest).count(": process started")
    assert 0 < running < 60
    assert wait_gone(pids_of(tmp_path)) == [] and tagged(tag) == []


# --- nothing survives the launcher -------------------------------------------------------------


def test_sigkill_of_tuilaunch_leaves_no_grandchild(write, tmp_path, launches):
    started, tag = launches
    path = launch_file(write, f"""
sl.add_action(ExecuteProcess(cmd=['sh', '-c', '{tag} 600 & wait'], name='wrapper'))
sl.add_action(ExecuteProcess(cmd=['{tag}', '600'], name='timed',
                             prefix='timeout 900'))
sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'setsid {tag} 600 & echo spawned; wait'],
                             name='daemonizer'))""")
    proc = start_headless(str(path), log_dir=tmp_path)
    started.append(proc)
    read_until(proc, "[daemonizer-3] spawned")
    deadline = time.monotonic() + 30
    while len(tagged(tag)) < 6:  # three sleeps, the wrapper shells and timeout
        assert time.monotonic() < deadline, tagged(tag)
        time.sleep(0.05)
    victims = tagged(tag)
    os.killpg(proc.pid, signal.SIGKILL)  # tuilaunch cannot clean up anything itself
    proc.wait()
    assert wait_gone(victims) == []


# --- safe files ---------------------------------------------------------------------------------


def test_a_process_name_cannot_escape_the_log_folder(write, tmp_path, launches):
    started, _ = launches
    path = launch_file(write, """
sl.declare_arg('robot', 'r1')
sl.add_action(ExecuteProcess(cmd=['echo', 'hello'], name=sl.arg('robot')))""")
    logs = tmp_path / "a" / "b" / "c"
    proc = start_headless(str(path), "robot:=../../../ESCAPED", log_dir=logs)
    started.append(proc)
    out = proc.communicate(timeout=60)[0]
    assert proc.returncode == 0, out
    escaped = [p for p in tmp_path.rglob("*ESCAPED*")]
    assert [p.parent for p in escaped] == [log_folder(logs)]  # its log, inside the folder
    assert escaped[0].read_text().endswith(" stdout hello\n")


def test_parameter_files_are_private_and_never_follow_a_symlink(write, tmp_path):
    from tuilaunch.engine.plan.params import write_parameter_file
    from tuilaunch.engine.plan.resolve import default_params_dir

    folder = default_params_dir()
    assert folder.stat().st_mode & 0o777 == 0o700
    assert default_params_dir() == folder  # one folder per tuilaunch process
    target = tmp_path / "precious"
    target.write_text("keep me")
    trap = folder / "node-1.yaml"
    trap.symlink_to(target)
    write_parameter_file(trap, {"a": 1})
    assert target.read_text() == "keep me"
    assert trap.stat().st_mode & 0o777 == 0o600 and not trap.is_symlink()
    assert "a: 1" in trap.read_text()
    trap.unlink()


# --- what an operator sees and gets back -------------------------------------------------------


def start_stubborn(write, tmp_path: Path, launches, keywords: str, *arguments: str)\
        -> tuple[subprocess.Popen[str], str]:
    """A headless launch of one process that ignores SIGINT and SIGTERM (ExecuteProcess
    `keywords` and launch `arguments` added), once it is ready: the run, and what it
    printed so far."""
    started, _ = launches
    script = stubborn_script(tmp_path)
    path = launch_file(write, f"sl.add_action(ExecuteProcess(cmd=['{script}'], "
                              f"name='stubborn'{keywords}))")
    proc = start_headless(str(path), *arguments, log_dir=tmp_path)
    started.append(proc)
    return proc, read_until(proc, "stubborn ready")


def test_per_process_timeouts_are_honoured_and_each_step_is_announced(write, tmp_path,
                                                                      launches):
    proc, _ = start_stubborn(write, tmp_path, launches,
                             ", sigterm_timeout='0.4', sigkill_timeout='0.6'")
    os.killpg(proc.pid, signal.SIGINT)
    out = proc.communicate(timeout=60)[0]
    # launch's words (ExecuteLocal), which CI scripts grep for; Ctrl+C's own SIGINT is not
    # announced, as in launch
    lines = out.splitlines()
    assert "[INFO] [stubborn-1]: sending signal 'SIGINT' to process[stubborn-1]" not in lines
    assert "[ERROR] [stubborn-1]: process[stubborn-1] failed to terminate '0.4' seconds " \
        "after receiving 'SIGINT', escalating to 'SIGTERM'" in lines, out
    assert "[INFO] [stubborn-1]: sending signal 'SIGTERM' to process[stubborn-1]" in lines
    assert "[ERROR] [stubborn-1]: process[stubborn-1] failed to terminate '0.6' seconds " \
        "after receiving 'SIGTERM', escalating to 'SIGKILL'" in lines, out
    assert "[INFO] [stubborn-1]: sending signal 'SIGKILL' to process[stubborn-1]" in lines
    # stopped as asked: said as a stop, not as an error, and a clean exit status
    assert re.search(r"\[INFO\] \[stubborn-1\]: process stopped \[pid \d+, killed by SIGKILL\]",
                     out)
    assert proc.returncode == 0


def test_timeouts_given_as_launch_arguments_apply_to_every_process(write, tmp_path, launches):
    """launch's defaults are LaunchConfiguration('sigterm_timeout', default=5) and the
    same for SIGKILL: `sigterm_timeout:=0.3` on the command line sets every process's that
    does not say its own, and is no undeclared argument."""
    proc, early = start_stubborn(write, tmp_path, launches, "", "sigterm_timeout:=0.3",
                                 "sigkill_timeout:=0.4")
    assert "not declared" not in early
    os.killpg(proc.pid, signal.SIGINT)
    out = proc.communicate(timeout=60)[0]
    assert "failed to terminate '0.3' seconds after receiving 'SIGINT', escalating to " \
        "'SIGTERM'" in out, out
    assert "failed to terminate '0.4' seconds after receiving 'SIGTERM', escalating to " \
        "'SIGKILL'" in out, out
    assert proc.returncode == 0


def test_second_and_third_ctrl_c_escalate_at_once(write, tmp_path, launches):
    proc, _ = start_stubborn(write, tmp_path, launches,
                             ", sigterm_timeout='60', sigkill_timeout='60'")
    os.kill(proc.pid, signal.SIGINT)
    read_until(proc, "Ctrl+C again sends SIGTERM now")
    os.kill(proc.pid, signal.SIGINT)
    read_until(proc, "received SIGINT again: sending SIGTERM now",
               "[WARN] [stubborn-1]: asked again: sending signal 'SIGTERM' to "
               "process[stubborn-1]")
    os.kill(proc.pid, signal.SIGINT)
    out = read_until(proc, "sending SIGKILL now", "killed by SIGKILL]")
    assert "failed to terminate" not in out  # no timeout was waited for
    proc.communicate(timeout=30)
    assert proc.returncode == 0


def test_exit_status_tells_a_clean_stop_from_a_lost_child(write, tmp_path, launches):
    started, _ = launches
    # slept in steps: a SIGINT landing between the print and one long sleep would be seen
    # only when that sleep returns (CPython's race), and the stop would need SIGTERM
    path = launch_file(write, """
sl.add_action(ExecuteProcess(cmd=['python3', '-c', 'import time; print("up", flush=True); '
                                  '[time.sleep(0.1) for _ in range(6000)]'], name='plain'))""")
    proc = start_headless(str(path), log_dir=tmp_path / "clean")
    started.append(proc)
    read_until(proc, "[plain-1] up")
    os.killpg(proc.pid, signal.SIGINT)
    out = proc.communicate(timeout=60)[0]
    assert "KeyboardInterrupt" in out  # the script died of the SIGINT tuilaunch sent
    assert re.search(r"\[INFO\] \[plain-1\]: process stopped \[pid \d+, killed by SIGINT\]", out)
    assert proc.returncode == 0
    path = launch_file(write, """
sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo up; kill -9 $$'], name='lost'))
sl.add_action(ExecuteProcess(cmd=['sleep', '600'], name='other'))""")
    proc = start_headless(str(path), log_dir=tmp_path / "lost")
    started.append(proc)
    out = read_until(proc, "[lost-1]: process has died [pid ")
    # ros2 launch's words (what scripts grep for), with the signal named
    assert re.search(r"\[ERROR\] \[lost-1\]: process has died \[pid \d+, exit code -9 \(killed "
                     r"by SIGKILL\), cmd 'sh -c echo up; kill -9 \$\$'\]\.", out), out
    os.killpg(proc.pid, signal.SIGINT)
    proc.communicate(timeout=60)
    assert proc.returncode == 1


def test_log_files_keep_the_bytes_the_screen_shows_clean_lines(write, tmp_path, launches):
    started, _ = launches
    path = launch_file(write, r"""
sl.add_action(ExecuteProcess(name='bytes', cmd=[
    'printf', '10%%\\r50%%\\r100%%\\nnul\\000byte\\n\\033[31mred\\033[0m\\n']))""")
    proc = start_headless(str(path), log_dir=tmp_path)
    started.append(proc)
    out = proc.communicate(timeout=60)[0]
    assert "[bytes-1] 100%\n" in out and "[bytes-1] nulbyte\n" in out
    assert "[bytes-1] red\n" in out  # not a terminal: colour codes are stripped
    logged = [line.split(b" ", 2)[2] for line in
              (log_folder(tmp_path) / "bytes-1.log").read_bytes().split(b"\n")[:-1]]
    # a line rewritten with \r keeps its last state; other bytes as written
    assert logged == [b"100%", b"nul\x00byte", b"\x1b[31mred\x1b[0m"]


# --- pipes, or a terminal ---------------------------------------------------------------------


def test_a_c_program_that_never_flushes_prints_live_only_through_a_terminal(write, tmp_path,
                                                                             launches):
    """As launch: pipes by default (printf held in its buffer, launch#188), a terminal for
    each stream with emulate_tty=True (printf live, stderr still apart)."""
    started, _ = launches
    source = tmp_path / "noflush.c"
    source.write_text('#include <stdio.h>\n#include <unistd.h>\n'
                      'int main(void) { printf("live %d\\n", isatty(1)); '
                      'fprintf(stderr, "apart %d\\n", isatty(2)); sleep(600); return 0; }\n')
    binary = tmp_path / "noflush"
    subprocess.run(["gcc", "-o", str(binary), str(source)], check=True)
    path = launch_file(write, f"""
sl.add_action(ExecuteProcess(cmd=['{binary}'], name='shown', emulate_tty=True))
sl.add_action(ExecuteProcess(cmd=['{binary}'], name='piped'))
sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'sleep 1; echo piped checked'], name='later'))""")
    proc = start_headless(str(path), log_dir=tmp_path)
    started.append(proc)
    seen = read_until(proc, "[shown-1] live 1", "[shown-1] apart 1", "[piped-2] apart 0",
                      "[later-3] piped checked")
    # with a pipe, printf holds its line in a buffer until exit: what launch#188 is about
    assert "[piped-2] live" not in seen
    log = (log_folder(tmp_path) / "shown-1.log").read_text()
    assert " stdout live 1\n" in log and " stderr apart 1\n" in log  # stderr kept apart
    os.killpg(proc.pid, signal.SIGINT)
    assert proc.wait(timeout=60) == 0


def test_threads_stay_constant_whatever_the_number_of_children(write, tmp_path):
    path = launch_file(write, """
for i in range(30):
    sl.add_action(ExecuteProcess(cmd=['sleep', '600'], name=f's{i}'))""")
    plan = resolve(load_file(str(path)), {}, params_dir=tmp_path / "params")
    supervisor = Supervisor(plan, tmp_path / "log")
    before = threading.active_count()
    during: list[int] = []

    async def scenario() -> int:
        run = asyncio.ensure_future(supervisor.run())
        deadline = time.monotonic() + 60
        while list(supervisor.states.values()).count("running") < 30:
            assert time.monotonic() < deadline
            await asyncio.sleep(0.05)
        during.append(threading.active_count())
        await supervisor.shutdown("test done")
        return await run

    assert asyncio.run(scenario()) == 0
    assert during == [before]


# --- one-line errors -------------------------------------------------------------------------


def test_bad_names_and_values_get_one_line_naming_file_line_and_character(write, tmp_path):
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher()
    sl.node('tuilaunch_demos', 'talker', name='my node')
    sl.node('tuilaunch_demos', 'talker', name='9lives')
    sl.node('tuilaunch_demos', 'talker', name='ok', namespace='/robot/été')
    sl.node('tuilaunch_demos', 'talker', name='fine', namespace='good_ns')
    return sl.launch_description()
""")
    result = run_cli(str(path), "--print")
    assert result.returncode == 3
    errors = [line for line in result.stderr.splitlines() if line.startswith("tuilaunch: error")]
    assert "test_launch.py:5:" in errors[0] and "' ' at position 3" in errors[0]
    assert "test_launch.py:6:" in errors[1] and "starts with the digit '9'" in errors[1]
    assert "test_launch.py:7:" in errors[2] and "'é' at position 8" in errors[2]
    assert len(errors) == 3  # /good_ns/fine is valid
    assert "Traceback" not in result.stderr


def test_include_cycle_respawn_delay_directory_and_log_folder_are_one_line(write, tmp_path):
    write(HEADER + "from launch.actions import IncludeLaunchDescription\n"
          "def generate_launch_description():\n    sl = SimpleLauncher()\n"
          f"    sl.include(launch_file='{tmp_path}/b.py')\n    return sl.launch_description()\n",
          "a.py")
    write(HEADER + "def generate_launch_description():\n    sl = SimpleLauncher()\n"
          f"    sl.include(launch_file='{tmp_path}/a.py')\n    return sl.launch_description()\n",
          "b.py")
    cycle = run_cli(str(tmp_path / "a.py"), "--print")
    assert cycle.returncode == 2 and "Traceback" not in cycle.stderr
    assert "include cycle: a.py -> b.py -> a.py" in cycle.stderr.splitlines()[0]
    soon = launch_file(write, "sl.add_action(ExecuteProcess(cmd=['true'], respawn=True, "
                              "respawn_delay='soon'))")
    result = run_cli(str(soon), "--print")
    assert result.returncode == 2
    assert "test_launch.py:" in result.stderr and "respawn_delay 'soon' is not a number" in \
        result.stderr and "Traceback" not in result.stderr
    folder = run_cli(str(tmp_path), "--headless")
    assert folder.returncode == 2 and "is a directory, not a launch file" in folder.stderr
    (tmp_path / "afile").write_text("")
    fine = launch_file(write, "sl.add_action(ExecuteProcess(cmd=['true']))")
    logs = run_cli(str(fine), "--headless",
                   env={"ROS_LOG_DIR": str(tmp_path / "afile" / "logs")})
    assert logs.returncode == 2 and "Traceback" not in logs.stderr
    assert "cannot create the log folder" in logs.stderr and "Not a directory" in logs.stderr


def test_a_bad_ros_domain_id_fails_the_ros_actions_not_the_launcher(write, tmp_path,
                                                                    launches):
    """rmw_fastrtps ends a process that makes a node in domain 300 (exit 1, no exception):
    tuilaunch's own ROS actions must fail with a line saying why, and the launch run on."""
    started, _ = launches
    # `exec`: a shell that forks `sleep` loses a SIGINT arriving between that fork and the
    # exec (the copy's handler takes it, then exec drops it) and waits for a sleep that
    # never got it: the stop needed SIGTERM, 3 runs in 5 on a busy machine
    path = launch_file(write, """
sl.add_action(ExecuteProcess(cmd=['sh', '-c', 'echo up; exec sleep 600'], name='plain'))
sl.call_service('/somewhere/reset')""")
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path), "ROS_DOMAIN_ID": "300"}
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=env, start_new_session=True)
    started.append(proc)
    out = read_until(proc, "[plain-1] up", "call_service /somewhere/reset failed: "
                     "ROS_DOMAIN_ID=300 is out of range (0-232)")
    assert proc.poll() is None  # still running its launch
    os.killpg(proc.pid, signal.SIGINT)
    out += proc.communicate(timeout=60)[0]
    assert re.search(r"\[INFO\] \[plain-1\]: process stopped \[pid \d+, killed by SIGINT\]", out)
