"""Sessions: the launch runs in a background server; the TUI and the commands are clients.

Real processes throughout: the server is started by the command line as a user would, the
TUI attaches on a pseudo-terminal or through Textual's pilot, and shell scripts drive the
commands.
"""

from __future__ import annotations

import asyncio
import json
import os
import pty
import select
import shutil
import signal
import socket
import stat
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TypeVar

import pytest
from textual.widgets import Input

from tuilaunch.client.link import open_link
from tuilaunch.client.remote_supervisor import RemoteSupervisor
from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.events import ProcessExited, Started, Stopping
from tuilaunch.engine.run.session import session_dir
from tuilaunch.engine.run.vocabulary.request import Request
from tuilaunch.engine.run.vocabulary.requests import Status
from tuilaunch.tui.app import make_app
from tuilaunch.tui.output_store import LEVELS, View

from ..conftest import run_cli, session_folders, wait_for
from .proc_tree import alive as _alive
from .proc_tree import end, servers_of
from .session_steps import start_here, stop_here
from .test_tui import until

R = TypeVar("R")

LAUNCH = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('word', 'alpha')
    sl.add_action(ExecuteProcess(name='ticker', cmd=[
        'sh', '-c', 'i=0; while true; do i=$((i+1)); echo tick $i; sleep 0.1; done']))
    sl.add_action(ExecuteProcess(name='early', cmd=[
        'sh', '-c', 'echo early bird; echo "[WARN] careful"']))
    sl.add_action(ExecuteProcess(name='echo', cmd=[
        'sh', '-c', 'echo word "$0"; exec sleep 600', sl.arg('word')]))
    return sl.launch_description()
"""


@pytest.fixture
def runtime(monkeypatch, tmp_path):
    """A private session folder (short: socket paths are limited to 108 bytes) and log
    folder; whatever a failing test left running is stopped afterwards."""
    folder = Path(tempfile.mkdtemp(prefix="tl"))
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(folder))
    monkeypatch.setenv("ROS_LOG_DIR", str(tmp_path / "log"))
    yield folder
    end([json.loads(info.read_text())["pid"]
         for info in (folder / "tuilaunch").glob("*.json")])
    # a server whose info was never written (it lost a race, or its test failed early) is
    # found by its log folder, which is this test's
    end(servers_of(tmp_path))
    shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture(scope="module")
def shared_session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path]]:
    """One session of LAUNCH (default arguments, as start_detached starts it) for the tests
    that leave it as they found it (they read it, or stop and continue its server): its
    name and its session folder."""
    root = tmp_path_factory.mktemp("shared")
    path = root / "test_launch.py"
    path.write_text(LAUNCH)
    with session_folders(root / "log") as folder:
        name = start_here(path)
        try:
            wait_state(name, "echo-3", "running")
            wait_state(name, "early-2", "exited")
            yield name, folder
        finally:
            stop_here(name, gone_ok=True)  # a failed test may have ended it


@pytest.fixture
def shared(shared_session: tuple[str, Path], runtime, monkeypatch) -> tuple[str, Path]:
    """The shared session, its folder this test's (in place of `runtime`'s)."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(shared_session[1]))
    return shared_session


def tl(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    done = run_cli(*args)
    if check:
        assert done.returncode == 0, done.stderr
    return done


def run_cli_together(*commands: tuple[str, ...]) -> list[subprocess.CompletedProcess[str]]:
    """Each command line run as run_cli runs it, all at once (they must not depend on one
    another): what each did, in order."""
    with ThreadPoolExecutor() as pool:
        return list(pool.map(lambda args: run_cli(*args), commands))


def asked(name: str, request: Request[R]) -> R:
    """The session's reply to `request`, read as a command reads it, from this process: a
    command's own start costs a quarter of a second of CPU, which the tests' many looks at
    a session's state need not pay. In a thread of its own (a Link runs its own event
    loop, and a test's may be running here)."""

    def ask() -> R:
        link = open_link(name)
        try:
            return link.request(request, short=True)
        finally:
            link.close()

    with ThreadPoolExecutor(max_workers=1) as pool:
        return pool.submit(ask).result()


def status(name: str) -> dict:
    """What `tuilaunch status NAME --json` says of the session, but each process's CPU and
    memory (which take the server 0.3 s to measure), read from this process. A test of the
    command itself runs it: cli_status."""
    return json.loads(json.dumps(asked(name, Status(resources=False)).to_json()))


def cli_status(name: str) -> dict:
    """`tuilaunch status NAME --json`, the command as a user runs it."""
    return json.loads(tl("status", name, "--json").stdout)


def pids(name: str) -> dict[str, int]:
    return {p["id"]: p["pid"] for p in status(name)["processes"] if p["pid"]}


def wait_state(name: str, process: str, state: str, timeout: float = 60) -> None:
    """Returns once the process (its id) is in `state`, as `tuilaunch wait` would, looking
    from this process: for a test's own steps, where the command is not what is tested."""
    def now() -> str | None:
        return next((p["state"] for p in status(name)["processes"] if p["id"] == process),
                    None)

    wait_for(lambda: now() == state, timeout, f"{process} {state} in {name}")


def detached_with(path: str, process: str) -> tuple[str, Path]:
    """A session of `path` started detached, once `process` runs: its name and its log
    folder, for a TUI to attach to."""
    name = start_here(path)
    wait_state(name, process, "running")
    return name, Path(status(name)["log_dir"])


def start_detached(write, *args: str) -> str:
    path = write(LAUNCH)
    name = start_here(path, *args)
    wait_state(name, "echo-3", "running")
    # started before echo, but a busy machine may run it later: its end is part of the start
    wait_state(name, "early-2", "exited")
    return name


class Terminal:
    """A command on a pseudo-terminal whose screen is read continuously, as a terminal's."""

    def __init__(self, *args: str, size: tuple[int, int] | None = None) -> None:
        """`size`: (columns, lines) the program is told, else the terminal's default."""
        self.master, slave = pty.openpty()
        env = {**os.environ, "TERM": "xterm-256color"}
        if size is not None:
            env.update(COLUMNS=str(size[0]), LINES=str(size[1]))
        self.proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", *args], stdin=slave,
                                     stdout=slave, stderr=slave, env=env,
                                     start_new_session=True)
        os.close(slave)
        self.screen = b""

    def read_until(self, marker: bytes, limit: float = 60.0) -> bytes:
        """What was printed up to and with the read that showed `marker`."""
        end = time.monotonic() + limit
        while marker not in self.screen:
            assert time.monotonic() < end, f"{marker!r} never appeared: {self.screen[-500:]!r}"
            self.pump(0.1)
        return self.screen

    def pump(self, wait: float) -> None:
        if select.select([self.master], [], [], wait)[0]:
            try:
                self.screen += os.read(self.master, 1 << 16)
            except OSError:  # the program is gone: no loop spinning on its closed side
                time.sleep(wait)

    def press_until_exit(self, key: bytes, limit: float = 60.0) -> int:
        """`key` (d, q) again every half second until the TUI exits: keys that come right
        after a burst it drops (the node's, typed with `i`) are dropped too."""
        end = time.monotonic() + limit
        while self.proc.poll() is None and time.monotonic() < end:
            os.write(self.master, key)
            self.pump(0.5)
        return self.wait_exit()

    def wait_exit(self, limit: float = 60.0) -> int:
        end = time.monotonic() + limit
        while self.proc.poll() is None:
            assert time.monotonic() < end, "the TUI never exited"
            self.pump(0.1)
        return self.proc.returncode

    def close(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait()
        os.close(self.master)


def test_a_shell_script_starts_waits_reads_status_and_stops(runtime, write):
    script = f"""
    set -eu
    TL="{sys.executable} -m tuilaunch"
    name=$($TL "$1" --detach --name scripted word:=beta)
    test "$name" = scripted
    $TL wait "$name" ticker running --timeout 30
    $TL wait "$name" early-2 exited --timeout 30
    pid=$($TL status "$name" --json | {sys.executable} -c '
import json, sys
print(next(p["pid"] for p in json.load(sys.stdin)["processes"] if p["id"] == "ticker-1"))')
    kill -0 "$pid"
    if $TL wait "$name" ticker-1 exited --timeout 0.3; then echo "wait lied"; exit 9; fi
    $TL logs "$name" echo-3 | grep -qx "word beta"
    $TL logs "$name" --level WARN | grep -qx "\\[early-2\\] \\[WARN\\] careful"
    $TL stop "$name"
    if kill -0 "$pid" 2>/dev/null; then echo "ticker survived"; exit 8; fi
    test "$($TL ls --json)" = "[]"
    echo ok
    """
    done = subprocess.run(["bash", "-c", script, "script", str(write(LAUNCH))],
                          capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.strip().endswith("ok")
    assert "ticker-1 is running, not exited, after 0.3 s" in done.stderr


def test_ls_names_sessions_and_the_socket_is_private(runtime, write):
    name = start_detached(write)
    assert name == "test_launch-1"
    second = start_detached(write, "--name", "other", "word:=x")
    listed = json.loads(tl("ls", "--json").stdout)
    assert [s["name"] for s in listed] == [name, second]
    assert listed[1]["arguments"] == {"word": "x"}
    assert listed[0]["counts"]["running"] == 2  # early-2 printed and exited
    folder = runtime / "tuilaunch"
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    assert stat.S_IMODE((folder / f"{name}.sock").stat().st_mode) == 0o600
    several = run_cli("attach")
    assert several.returncode == 2
    assert f"several sessions run: {name}, {second}" in several.stderr
    no_terminal = run_cli("attach", name)  # captured output is no terminal
    assert no_terminal.returncode == 2 and "attach needs a terminal" in no_terminal.stderr
    # a session of the same name cannot start twice
    again = run_cli(str(write(LAUNCH)), "--detach", "--name", "other")
    assert again.returncode == 2 and "already running" in again.stderr
    stop_here(second)
    stop_here(name)


def test_a_dead_server_leaves_no_node_and_ls_cleans_its_socket(runtime, write):
    name = start_detached(write)
    children = pids(name)
    server = status(name)["pid"]
    os.kill(server, signal.SIGKILL)
    wait_for(lambda: not any(_alive(p) for p in [server, *children.values()]))
    assert (runtime / "tuilaunch" / f"{name}.sock").exists()  # nobody removed it
    assert tl("ls").stdout.strip() == "no running sessions"
    assert not list((runtime / "tuilaunch").iterdir())
    missing = run_cli("status", name)
    assert missing.returncode == 2 and f"no running session named {name}" in missing.stderr


def test_a_stopped_server_makes_no_command_hang(shared):
    """A stray Ctrl+Z or `kill -STOP` on the server: its socket still accepts, nothing
    answers. `ls` lists it as not answering, the others say so in one line; none hangs.
    Once continued, it answers again."""
    name, _ = shared
    server = status(name)["pid"]
    os.kill(server, signal.SIGSTOP)
    try:
        started = time.monotonic()
        # the three asked at once: each waits out its own answer timeout, not the sum
        listed, listed_json, asked = run_cli_together(("ls",), ("ls", "--json"),
                                                      ("status", name))
        assert listed.returncode == 0
        row = next(line.split() for line in listed.stdout.splitlines() if line.startswith(name))
        assert row[1] == str(server) and row[4] == "?"
        assert f"session {name} did not answer within 3 s: its server (pid {server}) is " \
            "stopped" in listed.stderr
        assert f"kill -CONT {server}" in listed.stderr
        assert listed_json.returncode == 0, listed_json.stderr
        assert json.loads(listed_json.stdout)[0]["answering"] is False
        assert asked.returncode == 2 and "Traceback" not in asked.stderr
        assert asked.stderr.startswith(f"tuilaunch status: error: session {name} did not "
                                       "answer within 10 s")
        assert time.monotonic() - started < 60
    finally:
        os.kill(server, signal.SIGCONT)
    assert json.loads(tl("ls", "--json").stdout)[0]["answering"] is True


def test_kill_now_on_a_server_that_does_not_answer_kills_it_and_so_the_launch(runtime,
                                                                             write):
    """The TUI's "kill now" while the server is stopped: the client SIGKILLs the server,
    whose watchdog kills every node, instead of waiting for an answer that never comes."""
    path = str(write(LAUNCH))
    name = start_detached(write)
    children = pids(name)
    server = status(name)["pid"]

    async def scenario() -> RemoteSupervisor:
        remote = await RemoteSupervisor.open(name, Session(path, {}))
        os.kill(server, signal.SIGSTOP)
        asking = asyncio.ensure_future(remote.shutdown("test"))  # never answered
        await asyncio.sleep(0.2)
        await asyncio.to_thread(remote.kill_all)
        await asyncio.wait_for(remote.run(), 60)  # it ends: the server is gone
        asking.cancel()
        return remote

    remote = asyncio.run(scenario())
    assert remote.killed_server and not remote.lost
    wait_for(lambda: not any(_alive(p) for p in [server, *children.values()]))


def test_killed_tui_client_leaves_nodes_running_and_attach_shows_what_was_missed(
        runtime, write):
    name = start_detached(write)
    before = pids(name)
    terminal = Terminal("attach", name)
    try:
        terminal.read_until(b"ticker-1")
        os.kill(terminal.proc.pid, signal.SIGKILL)  # the ssh link and the client die hard
        terminal.proc.wait()
    finally:
        terminal.close()
    assert status(name)["counts"] == {"running": 2, "exited": 1}
    assert pids(name) == before  # the very same processes, never restarted
    log_dir = Path(status(name)["log_dir"])
    wait_for(lambda: "tick 40" in (log_dir / "ticker-1.log").read_text())

    async def attach_again() -> None:
        app = make_app(str(write(LAUNCH)), {}, log_dir, session_name=name)
        async with app.run_test(size=(100, 30)) as pilot:
            assert app.supervisor is not None
            assert app.supervisor.states["ticker-1"] == "running"
            assert app.supervisor.states["early-2"] == "exited"
            early = [line.text for line in app.store.lines(View("early-2"))]
            # the pane also shows the process's own events (started, exited)
            assert [t for t in early if "process" not in t] == ["early bird", "[WARN] careful"]
            ticks = [line.text for line in app.store.lines(View("ticker-1"))
                     if line.text.startswith("tick")]
            assert ticks[:40] == [f"tick {i}" for i in range(1, 41)]  # none missing
            # the tree shows states, and new lines keep coming
            tree_text = str(app.launch_tree.rows["ticker-1"].label)
            assert "running" in tree_text and str(before["ticker-1"]) in tree_text
            seen = len(ticks)
            for _ in range(200):
                await pilot.pause(0.05)
                ticks = [line.text for line in app.store.lines(View("ticker-1"))
                         if line.text.startswith("tick")]
                if len(ticks) > seen + 3:
                    break
            assert ticks == [f"tick {i}" for i in range(1, len(ticks) + 1)]  # no gap, no twice
            await pilot.press("d")
            await until(pilot, lambda: getattr(app.supervisor, "detached", False))
        assert app.detached

    asyncio.run(attach_again())
    assert pids(name) == before
    stop_here(name)


def test_stop_leaves_nothing_behind(runtime, write):
    path = write(LAUNCH.replace(
        "sl.declare_arg('word', 'alpha')",
        "sl.declare_arg('word', 'alpha')\n"
        "    sl.add_action(ExecuteProcess(name='family', cmd=[\n"
        "        'sh', '-c', 'sleep 600; echo never']))"))
    name = start_here(str(path))
    wait_state(name, "family-1", "running")
    info = status(name)
    group = [int(p) for p in subprocess.run(
        ["pgrep", "-g", str(info["processes"][0]["pid"])], capture_output=True,
        text=True).stdout.split()]
    assert len(group) == 2  # the shell and its sleep
    done = tl("stop", name)
    assert done.stdout.strip() == f"session {name} stopped"
    # stop returns once everything is gone: no waiting needed here
    leftover = [p for p in [info["pid"], *group, *pids_of(info)] if _alive(p)]
    assert leftover == []
    assert not list((runtime / "tuilaunch").iterdir())


def pids_of(info: dict) -> list[int]:
    return [p["pid"] for p in info["processes"] if p["pid"]]


def test_two_clients_see_the_same_relaunch(runtime, write):
    path = str(write(LAUNCH))
    name = start_detached(write)
    old_echo = pids(name)["echo-3"]
    log_dir = Path(status(name)["log_dir"])

    async def scenario() -> None:
        other = await RemoteSupervisor.open(name, Session(path, {}))
        seen: list = []
        other.subscribe(seen.append)
        other_task = asyncio.ensure_future(other.run())
        app = make_app(path, {}, log_dir, session_name=name)
        async with app.run_test(size=(100, 30)) as pilot:
            # the operator at the TUI edits word and applies
            preview = app.session.preview({"word": "gamma"})
            assert preview.diff is not None and preview.diff.stop == ["echo-3"]
            app.query_one("#arg-word", Input).value = "gamma"  # the form, as typed
            await pilot.pause()
            await pilot.press("f5")
            for _ in range(400):
                await pilot.pause(0.05)
                if any(e.kind == "started" and e.process == "echo-3" for e in seen):
                    break
            # the other client was told, resolved the same plan, and sees the new process
            assert other.session.arguments == {"word": "gamma"}
            kinds = [(e.kind, e.process) for e in seen]
            assert ("relaunched", None) in kinds
            assert kinds.index(("exited", "echo-3")) < kinds.index(("started", "echo-3"))
            assert other.states["echo-3"] == "running"
            # and the TUI shows the new output
            for _ in range(200):
                await pilot.pause(0.05)
                if "word gamma" in [line.text for line in app.store.lines(View("echo-3"))]:
                    break
            assert "word gamma" in [line.text for line in app.store.lines(View("echo-3"))]
            # now the other operator applies, and the TUI follows: tree, form and output
            assert other.session.preview({"word": "delta"}).plan is not None
            other.session.accept(other.session.preview({"word": "delta"}))
            diff = await other.replace_plan(other.session.plan)
            assert diff.stop == ["echo-3"] and "echo-3" in diff.start
            for _ in range(200):
                await pilot.pause(0.05)
                if "word delta" in [line.text for line in app.store.lines(View("echo-3"))]:
                    break
            assert app.session.arguments == {"word": "delta"}
            # the form is rebuilt on the next refresh (its field is away meanwhile)
            await until(pilot, lambda: app.query_one("#arg-word", Input).value == "delta")
            assert "word delta" in [line.text for line in app.store.lines(View("echo-3"))]
            await pilot.press("d")
            await until(pilot, lambda: getattr(app.supervisor, "detached", False))
        await other.detach()
        await other_task

    asyncio.run(scenario())
    now = status(name)
    assert now["arguments"] == {"word": "delta"}
    assert not _alive(old_echo) and pids(name)["echo-3"] != old_echo
    stop_here(name)


def test_a_client_that_stops_reading_never_holds_up_the_launch(runtime, write):
    # ticker floods, in lines long enough that the megabytes are written in seconds
    path = write(LAUNCH.replace("echo tick $i; sleep 0.1; done", f"echo tick $i {'x' * 200}; done"))
    name = start_here(str(path))
    log = Path(status(name)["log_dir"]) / "ticker-1.log"
    stalled = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    stalled.connect(str(runtime / "tuilaunch" / f"{name}.sock"))
    stalled.sendall(b'{"id": 1, "op": "subscribe"}\n')  # and then never reads
    try:
        wait_for(lambda: log.stat().st_size > 0)
        size = log.stat().st_size
        wait_for(lambda: log.stat().st_size > size + 5_000_000, 60)  # far past its buffers
        assert status(name)["counts"]["running"] == 2  # others are answered meanwhile
        stop_here(name)
    finally:
        stalled.close()


def test_hangup_of_a_foreground_tui_stops_all_unless_keep_on_hangup(runtime, write):
    path = str(write(LAUNCH))
    terminal = Terminal(path)
    try:
        terminal.read_until(b"2 running")
        name = session_dir.live_sessions()[0]
        children = pids(name)
        os.kill(terminal.proc.pid, signal.SIGHUP)
        terminal.wait_exit()
        wait_for(lambda: not any(_alive(p) for p in children))
        assert tl("ls").stdout.strip() == "no running sessions"
    finally:
        terminal.close()
    terminal = Terminal(path, "--keep-on-hangup", "--name", "kept")
    try:
        terminal.read_until(b"2 running")
        children = pids("kept")
        os.kill(terminal.proc.pid, signal.SIGHUP)
        terminal.wait_exit()
        assert pids("kept") == children
    finally:
        terminal.close()
    # a TUI that only attached leaves the launch running when its terminal goes or when
    # it is told to terminate (two such TUIs, attached at once)
    attached = {how: Terminal("attach", "kept") for how in (signal.SIGHUP, signal.SIGTERM)}
    try:
        for how, terminal in attached.items():
            terminal.read_until(b"2 running")
            os.kill(terminal.proc.pid, how)
        for terminal in attached.values():
            assert terminal.wait_exit() == 0
    finally:
        for terminal in attached.values():
            terminal.close()
    assert pids("kept") == children
    stop_here("kept")


def test_a_file_named_like_a_command_is_taken_as_the_file(runtime, write, tmp_path):
    """An existing file wins over a command word, as it did before commands existed."""
    (tmp_path / "status").write_text(write(LAUNCH).read_text())
    done = subprocess.run([sys.executable, "-m", "tuilaunch", "status", "--print"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("status: 3 of 3 processes will run")
    elsewhere = run_cli("status")
    assert elsewhere.returncode == 2
    assert elsewhere.stderr.startswith("tuilaunch status: error: no running session")


LIFECYCLE_NODE = """
import rclpy
from rclpy.lifecycle import LifecycleNode

rclpy.init()
node = LifecycleNode('lc')

def bring_up():
    timer.cancel()
    node.trigger_configure()
    node.trigger_activate()
    print('active now', flush=True)

timer = node.create_timer(1.0, bring_up)
try:
    rclpy.spin(node)
except BaseException:
    pass
"""


def test_wait_for_a_lifecycle_state_asks_the_node(runtime, write, tmp_path):
    script = tmp_path / "lc_node.py"
    script.write_text(LIFECYCLE_NODE)
    path = write(f"""
        from launch import LaunchDescription
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            return LaunchDescription([ExecuteProcess(name='lc', cmd=[{sys.executable!r},
                                                                     {str(script)!r}])])
        """)
    name = start_here(str(path))
    try:
        tl("wait", name, "/lc", "active", "--timeout", "60")
        assert "active now" in tl("logs", name, "lc-1").stdout
        late = run_cli("wait", name, "lc-1", "finalized", "--timeout", "0.5")
        assert late.returncode == 1
        assert late.stderr.strip() == "tuilaunch wait: /lc is active, not finalized"
        wrong = run_cli("wait", name, "lc-1", "asleep")
        assert wrong.returncode == 2 and "unknown state 'asleep'" in wrong.stderr
        missing = run_cli("restart", name, "nobody")
        assert missing.returncode == 2 and "no process 'nobody'" in missing.stderr
        assert "lc-1" in missing.stderr  # the hint names the processes there are
    finally:
        stop_here(name)


def test_logs_follow_joins_the_file_and_the_live_stream_without_gap(runtime, write):
    name = start_detached(write)
    wait_state(name, "ticker-1", "running")
    follower = subprocess.Popen([sys.executable, "-m", "tuilaunch", "logs", name, "ticker",
                                 "-f"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)
    try:
        lines = []
        assert follower.stdout is not None
        while len(lines) < 31:
            lines.append(follower.stdout.readline().rstrip("\n"))
        assert lines[0].startswith("[INFO] [ticker-1]: process started with pid [")
        assert lines[1:] == [f"tick {i}" for i in range(1, 31)]
        old = pids(name)["ticker-1"]
        assert tl("restart", name, "ticker").stdout.strip() == "ticker-1: running"
        assert pids(name)["ticker-1"] != old and not _alive(old)
        while lines[-1] != "tick 1":  # the new process counts from 1 again, in the stream
            lines.append(follower.stdout.readline().rstrip("\n"))
        stop_here(name)
        _, errors = follower.communicate(timeout=30)  # -f ends with the session
        assert follower.returncode == 0, errors
    finally:
        if follower.poll() is None:
            follower.kill()
            follower.wait()
    assert run_cli("logs", name).returncode == 2  # gone: nothing to read from


def test_logs_filters_by_time_and_level(shared):
    name, _ = shared
    everything = tl("logs", name).stdout.splitlines()
    assert "[early-2] early bird" in everything and "[echo-3] word alpha" in everything
    assert tl("logs", name, "--level", "warn").stdout.splitlines() == [
        "[early-2] [WARN] careful"]
    later = str(time.time() + 3600)
    assert tl("logs", name, "--since", later).stdout == ""
    assert "[early-2] early bird" in tl("logs", name, "--since", "1h").stdout
    bad = run_cli("logs", name, "--since", "yesterday-ish")
    assert bad.returncode == 2 and "--since 'yesterday-ish' is not a time" in bad.stderr


@pytest.mark.skipif(os.getuid() != 0, reason="needs root to connect as another user")
def test_the_server_refuses_another_users_connection(shared):
    name, runtime = shared
    # the session folder stays 0700 (each session command makes it so again, the server's
    # too): to reach the uid check, the socket is linked into a folder anyone may enter
    opened = Path(tempfile.mkdtemp(prefix="tlopen", dir=runtime.parent))
    try:
        opened.chmod(0o755)
        os.link(runtime / "tuilaunch" / f"{name}.sock", opened / "s.sock")
        (opened / "s.sock").chmod(0o666)
        probe = (
            "import os, socket, sys\n"
            "os.setgid(65534); os.setuid(65534)\n"
            "s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM); s.settimeout(10)\n"
            "s.connect(sys.argv[1]); print(repr(s.recv(100)))\n")
        done = subprocess.run([sys.executable, "-c", probe, str(opened / "s.sock")],
                              capture_output=True, text=True, timeout=30)
        assert done.returncode == 0, done.stderr
        assert done.stdout.strip() == "b''"  # closed at once: no hello, no status, nothing
        assert status(name)["name"] == name  # its owner is still served
    finally:
        shutil.rmtree(opened, ignore_errors=True)


def test_a_client_queue_is_bounded_and_cuts_loose_a_client_that_reads_nothing():
    from tuilaunch.engine.run.events import Output, Respawning
    from tuilaunch.engine.run.session.session_server import CLIENT_MAX_EVENTS, ClientQueue

    async def scenario() -> None:
        cut: list[bool] = []
        queue = ClientQueue(max_lines=100, on_overflow=lambda: cut.append(True))
        for i in range(50):
            queue(Output("flood", stream="stdout", lines=[f"{i} {n}" for n in
                                                                   range(10)]))
        events = queue.take()
        assert events[0].kind == "dropped" and events[0].code == 400  # counted, not kept
        assert sum(len(e.lines) for e in events[1:]) == 100
        assert events[-1].lines[-1] == "49 9"  # the newest lines are the ones kept
        for _ in range(CLIENT_MAX_EVENTS + 5):
            queue(Respawning("crashy"))
        assert cut == [True] and queue.overflowed

    asyncio.run(scenario())


STUBBORN = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='stubborn', cmd=[
        'sh', '-c', 'trap "" INT; echo holding out; while true; do sleep 0.1; done'])])
"""


def test_kill_during_a_shutdown_sends_sigkill_at_once(runtime, write):
    path = str(write(STUBBORN))
    name = start_here(path)
    wait_state(name, "stubborn-1", "running")

    async def scenario() -> list:
        client = await RemoteSupervisor.open(name, Session(path, {}))
        seen: list = []
        client.subscribe(seen.append)
        running = asyncio.ensure_future(client.run())
        stopping = asyncio.ensure_future(client.shutdown("test"))
        for _ in range(100):  # SIGINT has been sent and ignored
            await asyncio.sleep(0.05)
            if any(e.kind == "shutdown" for e in seen):
                break
        client.kill_all()  # what the TUI's second q does: no more waiting
        await stopping
        await running  # the session ended
        return seen

    seen = asyncio.run(scenario())
    exits = [e for e in seen if e.kind == "exited" and e.process == "stubborn-1"]
    assert [e.reason for e in exits] == ["killed by SIGKILL"]
    assert tl("ls").stdout.strip() == "no running sessions"


def test_log_tails_are_read_backwards_up_to_the_given_size(tmp_path):
    from tuilaunch.engine.run.session.log_reader import read_lines, tail_lines

    log = tmp_path / "n-1.log"
    log.write_text("".join(f"{1000 + i}.5 stdout line {i} {'x' * (i % 50)}\n"
                           for i in range(20_000)))
    end = log.read_text().index("16000.5 stdout line 15000 ")  # bytes: the text is ASCII
    tail = tail_lines(log, end, 5000)
    assert [line.text.split()[1] for line in tail] == [str(i) for i in range(10_000, 15_000)]
    assert tail[0].time == 11_000.5 and tail[0].stream == "stdout"
    assert len(tail_lines(log, end, 100_000)) == 15_000  # asked for more than there is
    assert [line.text for line in read_lines(log, 150)][:1] == ["line 0 "]
    with open(log, "a") as handle:
        handle.write("1.0 stdout half a li")  # being written: not a line yet
    assert sum(1 for _ in read_lines(log)) == 20_000


def test_two_sessions_started_with_one_name_at_once_one_wins(runtime, write):
    path = str(write(LAUNCH))
    starts = [subprocess.Popen([sys.executable, "-m", "tuilaunch", path, "--detach", "--name",
                                "twin"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True) for _ in range(2)]
    results = sorted((p.wait(timeout=60), *p.communicate()) for p in starts)
    assert [code for code, _, _ in results] == [0, 2]
    assert results[0][1].strip() == "twin"
    assert "a session named twin is already running" in results[1][2]
    assert [s["name"] for s in json.loads(tl("ls", "--json").stdout)] == ["twin"]
    assert status("twin")["counts"]["running"] >= 1  # the winner is the one that answers
    stop_here("twin")
    assert not list((runtime / "tuilaunch").iterdir())


def test_two_launches_of_one_file_started_at_once_take_two_names(runtime, write):
    """A name is reserved from the moment it is picked, not once its server is up: two
    TUIs (and two --detach) of one file started in the same second both run, under the
    next free names, where the second failed 'a session named ... is already running'."""
    path = str(write(LAUNCH))
    stem = Path(path).name.removesuffix(".py")
    terminals = [Terminal(path) for _ in range(2)]
    try:
        for terminal in terminals:
            terminal.read_until(b"2 running")
        names = sorted(s["name"] for s in json.loads(tl("ls", "--json").stdout))
        assert names == [f"{stem}-1", f"{stem}-2"]
        starts = [subprocess.Popen([sys.executable, "-m", "tuilaunch", path, "--detach"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
                  for _ in range(2)]
        results = sorted((p.wait(timeout=60), *p.communicate()) for p in starts)
        assert [(code, out.strip(), err) for code, out, err in results] == [
            (0, f"{stem}-3", ""), (0, f"{stem}-4", "")]
        for name in (f"{stem}-3", f"{stem}-4"):
            wait_state(name, "echo-3", "running")
            stop_here(name)
    finally:
        for terminal in terminals:
            terminal.close()


def test_a_session_loads_its_file_with_the_command_line_ros2_launch_would_give(
        runtime, write):
    path = write("""
        import sys
        from launch import LaunchDescription
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            return LaunchDescription([ExecuteProcess(name='argv', cmd=[
                'echo', ' '.join(sys.argv[2:])])])
        """)
    name = tl(str(path), "--detach", "robots:=r1;r2").stdout.strip()
    wait_state(name, "argv-1", "exited")
    assert f"\n{path} robots:=r1;r2\n" in tl("logs", name, "argv-1").stdout
    stop_here(name)


LIFECYCLE_SESSION = """
from launch import LaunchDescription
from launch_ros.actions import LifecycleNode
def generate_launch_description():
    return LaunchDescription([LifecycleNode(package='tuilaunch_demos',
                                            executable='lifecycle_talker', name='lc',
                                            namespace='')])
"""


def test_an_attached_client_follows_lifecycle_states_and_asks_for_transitions(
        runtime, write):
    path = str(write(LIFECYCLE_SESSION))
    name = start_here(path)
    try:
        tl("wait", name, "/lc", "unconfigured", "--timeout", "60")

        async def scenario() -> tuple[dict, dict, bool, bool]:
            client = await RemoteSupervisor.open(name, Session(path, {}))
            seen: list = []
            client.subscribe(seen.append)
            running = asyncio.ensure_future(client.run())
            for _ in range(200):  # the server's tracker has heard the node by now, or soon
                if client.lifecycle.states.get("lc-1") == "unconfigured":
                    break
                await asyncio.sleep(0.05)
            before = dict(client.lifecycle.states)
            configured = await client.lifecycle.request("lc-1", "configure")
            for _ in range(200):
                if client.lifecycle.states.get("lc-1") == "inactive":
                    break
                await asyncio.sleep(0.05)
            after = dict(client.lifecycle.states)
            # a transition the node's state does not offer is refused, not sent
            refused = await client.lifecycle.request("lc-1", "deactivate")
            await client.detach()
            await running
            return before, after, configured, refused

        before, after, configured, refused = asyncio.run(scenario())
        assert before == {"lc-1": "unconfigured"}
        assert configured is True and after == {"lc-1": "inactive"}
        assert refused is False
        tl("wait", name, "/lc", "inactive", "--timeout", "60")
    finally:
        stop_here(name)


def test_attach_shows_progress_bars_and_bad_bytes_as_the_live_pane_does(runtime, write):
    """The lines printed before attaching come from the log files, which keep the raw bytes
    but for a line rewritten with `\\r`, of which they keep the last state; the pane shows
    them as a terminal would."""
    path = write("""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='bar', cmd=['printf',
        'load 10%%\\\\rload 50%%\\\\rload 100%%\\\\n\\\\377bad\\\\000byte\\\\ndone\\\\n'])])
""")
    name = start_here(str(path))
    wait_state(name, "bar-1", "exited")
    log_dir = Path(status(name)["log_dir"])
    logged = (log_dir / "bar-1.log").read_bytes()
    assert b" load 100%\n" in logged and b"load 10%" not in logged

    async def attach() -> None:
        app = make_app(str(path), {}, log_dir, session_name=name)
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.pause()
            shown = [line.text for line in app.store.lines(View("bar-1"))
                     if "process" not in line.text]
            assert shown == ["load 100%", "\ufffdbadbyte", "done"]
            await pilot.press("d")
            await until(pilot, lambda: getattr(app.supervisor, "detached", False))

    asyncio.run(attach())
    stop_here(name)


def test_a_stop_asked_elsewhere_is_not_shown_as_a_crash(runtime, write):
    """Another operator stops a node, or `tuilaunch stop` stops the session: an attached TUI
    shows those processes stopped (an INFO line), not failed in red as a crash would be."""
    path = str(write(LAUNCH))
    name = start_detached(write)
    log_dir = Path(status(name)["log_dir"])

    async def scenario() -> None:
        other = await RemoteSupervisor.open(name, Session(path, {}))
        other_task = asyncio.ensure_future(other.run())
        app = make_app(path, {}, log_dir, session_name=name)
        async with app.run_test(size=(80, 24)) as pilot:
            await other.stop("ticker-1")
            died: list = []
            for _ in range(600):
                await pilot.pause(0.05)
                died = [line for line in app.store.lines(View("ticker-1"))
                        if line.event and ("died" in line.text or "stopped" in line.text)]
                if died:
                    break
            assert died and LEVELS[died[-1].level] == "INFO", died
            assert "process stopped [pid" in died[-1].text
            assert app.launch_tree.states["ticker-1"] == "exited"
            stopper = await asyncio.create_subprocess_exec(
                sys.executable, "-m", "tuilaunch", "stop", name)
            for _ in range(600):
                await pilot.pause(0.05)
                if app.launch_tree.states.get("echo-3") != "running":
                    break
            assert app.launch_tree.states["echo-3"] == "exited"
            assert await stopper.wait() == 0
        await other_task

    asyncio.run(scenario())


def test_a_session_whose_files_were_removed_puts_them_back_and_outlives_a_logout(
        runtime, write, monkeypatch):
    """logind removes $XDG_RUNTIME_DIR when the user's last login ends (the ssh logout after
    --detach); a tmp cleaner or an rm removes a socket. The session stays reachable. At the
    logout logind unmounts $XDG_RUNTIME_DIR and makes it anew, empty, at the next login:
    the session is found there again."""
    # the fallback while the folder is away; short: a socket path must fit in 108 bytes
    # (pytest-xdist's tmp_path is longer)
    ros_home = Path(tempfile.mkdtemp(prefix="tlh"))
    monkeypatch.setenv("ROS_HOME", str(ros_home))
    try:
        name = start_detached(write)
        before = pids(name)
        shutil.rmtree(runtime / "tuilaunch")
        wait_for(lambda: run_cli("status", name).returncode == 0)
        assert pids(name) == before
        assert stat.S_IMODE(os.stat(runtime / "tuilaunch").st_mode) == 0o700
        assert stat.S_IMODE(os.stat(runtime / "tuilaunch" / f"{name}.sock").st_mode) == 0o600
        assert tl("ls").stdout.count(name) == 1
        (runtime / "tuilaunch" / f"{name}.sock").unlink()  # only the socket, this time
        wait_for(lambda: run_cli("status", name).returncode == 0)

        # the logout: the whole folder goes
        shutil.rmtree(runtime)
        # the server looks while the folder is away, too: it listens in the fallback
        wait_for(lambda: (ros_home / "tuilaunch" / f"{name}.sock").exists(),
                 what="the socket put back in the fallback folder")
        runtime.mkdir(mode=0o700)  # the next login
        wait_for(lambda: run_cli("status", name).returncode == 0)
        assert pids(name) == before
        assert tl("ls").stdout.count(name) == 1
        # nothing left there once the server has moved back (it tidies up just after)
        wait_for(lambda: not list((ros_home / "tuilaunch").iterdir()),
                 what="the fallback folder emptied")
        stop_here(name)
        assert not any(_alive(pid) for pid in before.values())
        assert not list((runtime / "tuilaunch").iterdir())  # and it cleans up after itself
    finally:
        shutil.rmtree(ros_home, ignore_errors=True)


TWO_PANES = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    for side in ('left', 'right'):
        sl.add_action(ExecuteProcess(name=side, cmd=[
            'sh', '-c', 'i=0; while true; do i=$((i+1)); echo $0 $i; sleep 0.02; done', side]))
    return sl.launch_description()
"""


def test_a_client_is_sent_only_the_pane_it_shows_and_reads_the_others_when_shown(
        runtime, write):
    """A display over a link shows one pane: the server sends no other process's lines;
    when it switches panes, the lines it was not sent are read from the log file, so the
    pane shown has every line, in order, none twice."""
    path = str(write(TWO_PANES))
    name = start_here(path)
    wait_state(name, "right-2", "running")

    def numbers(seen: list, process: str) -> list[int]:
        return [int(line.split()[1]) for e in seen if e.kind == "output"
                and e.process == process for line in e.lines]

    async def scenario() -> None:
        client = await RemoteSupervisor.open(name, Session(path, {}))
        seen: list = []
        everything: list = []
        client.subscribe(seen.append)
        client.subscribe(everything.append)
        task = asyncio.ensure_future(client.run())

        async def until_true(check, limit: float = 60.0) -> None:
            end = time.monotonic() + limit
            while not check():
                assert time.monotonic() < end, "never happened"
                await asyncio.sleep(0.05)

        await client.show("left-1")
        await until_true(lambda: len(numbers(seen, "left-1")) > 20)
        seen.clear()
        await until_true(lambda: len(numbers(seen, "left-1")) > 50)  # a second or more
        assert numbers(seen, "right-2") == []  # not on screen: not sent
        await client.show("right-2")
        await until_true(lambda: len(numbers(seen, "right-2")) > 100)
        # what it was not sent came from the log file: from the first line on, every
        # line once and in order (the replay at attach, the events, the file's part)
        right = numbers(client.history, "right-2") + numbers(everything, "right-2")
        assert right == list(range(1, len(right) + 1))
        await client.detach()
        await task

    asyncio.run(scenario())
    stop_here(name)


SLOW_STOP = """
import signal, sys, time, os
from pathlib import Path
def on_sigint(*_):
    # a node saving its state on SIGINT: it ends once the test lets it
    while not Path(os.environ["RELEASE"]).exists():
        time.sleep(0.05)
    sys.exit(0)
signal.signal(signal.SIGINT, on_sigint)
print("up", flush=True)
while True:
    signal.pause()
"""


def test_a_stop_in_progress_is_stopping_for_every_client_and_for_status(runtime, write,
                                                                          tmp_path):
    """The engine says when a stop begins: another client's tree, `status` and `wait`
    see "stopping" (with its pid) until the process has ended, whoever asked."""
    release = tmp_path / "release"
    node = write(SLOW_STOP, "slow_node.py")
    path = write(f"""
        from simple_launch import SimpleLauncher
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            sl = SimpleLauncher()
            sl.add_action(ExecuteProcess(name='slow', cmd=[{sys.executable!r}, {str(node)!r}],
                                         additional_env={{'RELEASE': {str(release)!r}}},
                                         sigterm_timeout='120'))
            return sl.launch_description()
        """)
    name, _ = detached_with(str(path), "slow-1")
    old = pids(name)["slow-1"]

    async def scenario() -> None:
        other = await RemoteSupervisor.open(name, Session(str(path), {}))
        seen: list = []
        other.subscribe(seen.append)
        task = asyncio.ensure_future(other.run())
        restart = await asyncio.create_subprocess_exec(
            sys.executable, "-m", "tuilaunch", "restart", name, "slow-1")
        waited = await asyncio.to_thread(tl, "wait", name, "slow-1", "stopping",
                                         "--timeout", "60")
        assert waited.returncode == 0
        now = {p["id"]: p for p in (await asyncio.to_thread(cli_status, name))["processes"]}
        assert (now["slow-1"]["state"], now["slow-1"]["pid"]) == ("stopping", old)
        for _ in range(600):
            if other.states.get("slow-1") == "stopping":
                break
            await asyncio.sleep(0.05)
        assert other.states["slow-1"] == "stopping"
        release.touch()
        assert await asyncio.wait_for(restart.wait(), 120) == 0
        for _ in range(600):
            if other.states.get("slow-1") == "running" and any(
                    isinstance(e, Started) and e.process == "slow-1" for e in seen):
                break
            await asyncio.sleep(0.05)
        life = [type(e) for e in seen if e.process == "slow-1" and isinstance(
            e, (Stopping, ProcessExited, Started))]
        assert life == [Stopping, ProcessExited, Started]
        assert [e.pid for e in seen if isinstance(e, Stopping)] == [old]
        await other.detach()
        await task

    asyncio.run(scenario())
    assert status(name)["processes"][0]["state"] == "running"
    stop_here(name)
