"""Sessions on another machine through a real sshd: `[HOST:]NAME` addresses for every
session command, `attach HOST:NAME`, and a dropped link that stops nothing.

"robot1" is an sshd on 127.0.0.1 (tests/integration/sshd.py) with its own session folder; its
sessions
are started as a user logged in there would, and reached only through `ssh robot1`.
"""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
from textual.widgets import Input

from tuilaunch.client import remote_supervisor
from tuilaunch.engine.run.event_buffer import EventBuffer
from tuilaunch.engine.run.events import Event, Output, Resources
from tuilaunch.tui import status_line
from tuilaunch.tui.app import make_app
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.dialogs import QuitScreen
from tuilaunch.tui.session_view import pane_save_dir

from ..conftest import run_cli, wait_for
from .session_steps import start_here
from .sshd import Machine, Machines, alive, free_port, machines_fixture, proxies_on  # noqa: F401
from .test_sessions import Terminal, run_cli_together, status, wait_state
from .test_tui import until

LAUNCH = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(name='ticker', cmd=[
        'sh', '-c', 'i=0; while true; do i=$((i+1)); echo tick $i; sleep 0.2; done']))
    sl.add_action(ExecuteProcess(name='quiet', cmd=['sleep', '600']))
    return sl.launch_description()
"""


def there(machine: Machine) -> dict[str, str]:
    """The environment of a user logged in on `machine`."""
    return {"XDG_RUNTIME_DIR": str(machine.runtime),
            "ROS_LOG_DIR": str(machine.folder / "roslog")}


@contextmanager
def logged_in(machine: Machine) -> Iterator[None]:
    """This process's environment is that of a user logged in on `machine` meanwhile."""
    with pytest.MonkeyPatch.context() as patch:
        for key, value in there(machine).items():
            patch.setenv(key, value)
        yield


def status_there(machine: Machine, name: str) -> dict:
    """The session's status as `tuilaunch status NAME --json` says it on `machine` (read
    from this process; for a test's own steps, where the command is not what is tested)."""
    with logged_in(machine):
        return status(name)


def start_on(machine: Machine, write, name: str) -> int:
    """A session started on `machine` (as `tuilaunch FILE --detach` there, from this
    process: the tests' subject is what is done to it through the link); its server's pid."""
    path = write(LAUNCH)
    with logged_in(machine):
        start_here(path, "--name", name)
        wait_state(name, "ticker-1", "running")
    return machine.server_pid(name)


def test_session_commands_work_through_the_ssh_link(machines: Machines, write,
                                                    tmp_path):
    server = start_on(machines["robot1"], write, "far")
    # asked at once: none changes what the others see
    listed, here, status, topics = run_cli_together(
        ("ls", "robot1", "--json"), ("ls",), ("status", "robot1:far", "--json"),
        ("topics", "robot1:far", "--json"))
    assert listed.returncode == 0, listed.stderr
    assert [s["name"] for s in json.loads(listed.stdout)] == ["far"]
    # not listed here: the session is robot1's
    assert "far" not in here.stdout

    assert status.returncode == 0, status.stderr
    states = {p["id"]: p["state"] for p in json.loads(status.stdout)["processes"]}
    assert states == {"ticker-1": "running", "quiet-2": "running"}

    # the ROS inspector's commands too (no ROS node runs here: no topic of ours)
    assert topics.returncode == 0, topics.stderr
    assert isinstance(json.loads(topics.stdout), list | dict)

    wait_for(lambda: "tick 3\n" in run_cli("logs", "robot1:far", "ticker-1").stdout)
    logs = run_cli("logs", "robot1:far", "ticker-1").stdout.splitlines()
    assert logs[0].startswith("[INFO] [ticker-1]: process started with pid [")  # launch.log
    assert logs[1:4] == ["tick 1", "tick 2", "tick 3"]
    every = run_cli("logs", "robot1:far").stdout
    assert "[ticker-1] tick 1" in every

    # a wait through the link that times out says the state it saw
    done = run_cli("wait", "robot1:far", "ticker-1", "exited", "--timeout", "1")
    assert done.returncode == 1
    assert "ticker-1 is running, not exited" in done.stderr

    # failures, each one line naming the host, while the session runs there
    remote_failures_are_one_line_naming_the_host(machines, tmp_path)

    restarted = run_cli("restart", "robot1:far", "ticker")
    assert restarted.returncode == 0, restarted.stderr
    assert "ticker-1: running" in restarted.stdout
    assert run_cli("wait", "robot1:far", "quiet-2", "running", "--timeout", "30")\
        .returncode == 0

    stopped = run_cli("stop", "robot1:far")
    assert stopped.returncode == 0, stopped.stderr
    assert "session robot1:far stopped" in stopped.stdout
    wait_for(lambda: not alive(server))
    # nothing of the launch is left over there: no node, no server, no proxy
    wait_for(lambda: running_on(machines["robot1"]) == [])
    assert json.loads(run_cli("ls", "robot1", "--json").stdout) == []


def remote_failures_are_one_line_naming_the_host(machines: Machines, tmp_path: Path) -> None:
    """Asked while robot1 runs the session "far": a session it does not run, a machine
    nobody listens on, a key it refuses, a tuilaunch it does not have."""
    unknown = run_cli("status", "robot1:nothere")
    assert unknown.returncode == 2
    assert "robot1: no running session named nothere" in unknown.stderr
    assert "Traceback" not in unknown.stderr

    # a machine nobody listens on
    config = machines.ssh_config
    config.write_text(config.read_text() + machines.host_entry("gone", 1))
    unreachable = run_cli("ls", "gone")
    assert unreachable.returncode == 2
    assert "cannot reach gone" in unreachable.stderr.splitlines()[0]

    # a key robot1 does not accept
    from .sshd import keygen

    other = tmp_path / "other_key"
    keygen(other)
    config.write_text(config.read_text() + machines.host_entry(
        "stranger", machines["robot1"].port, other))
    refused = run_cli("status", "stranger:far")
    assert refused.returncode == 2
    assert "stranger refused the login" in refused.stderr.splitlines()[0]

    missing = run_cli("logs", "robot1:far", env={"TUILAUNCH_REMOTE": "/nonexistent/tuilaunch"})
    assert missing.returncode == 2
    assert "robot1: tuilaunch not found there" in missing.stderr.splitlines()[0]
    for done in (unknown, unreachable, refused, missing):
        assert "Traceback" not in done.stderr


def running_on(machine: Machine) -> list[int]:
    """Every live process started under `machine` (its session folder in its environment)."""
    marker = f"XDG_RUNTIME_DIR={machine.runtime}".encode()
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            environ = (entry / "environ").read_bytes()
        except OSError:
            continue
        if marker in environ.split(b"\0") and alive(int(entry.name)):
            found.append(int(entry.name))
    return found


def test_attach_through_ssh_survives_a_dropped_link(machines: Machines, write, monkeypatch):
    """The TUI here, the launch on robot1: the link dropped says so, stops nothing, and
    once back shows what happened meanwhile, nothing twice and nothing missed."""
    robot = machines["robot1"]
    server = start_on(robot, write, "far")
    status = status_there(robot, "far")
    before = {p["id"]: p["pid"] for p in status["processes"]}
    # reconnect only when asked (R), so what happens meanwhile surely happens meanwhile
    monkeypatch.setattr(remote_supervisor, "RETRY_FIRST", 600.0)

    def ticks(app) -> list[str]:
        return [line.text for line in app.store.lines(View("ticker-1"))
                if line.text.startswith("tick")]

    async def attached() -> None:
        app = make_app(status["file"], status["arguments"], Path(status["log_dir"]),
                       session_name="far", session_host="robot1")
        async with app.run_test(size=(100, 30)) as pilot:
            # the Nodes tab watches CPU and memory: the server says them once the watch
            # begins (a second after it is asked), then as they change
            await until(pilot, lambda: app.supervisor is not None)
            assert app.supervisor is not None
            usage: list[Event] = []
            app.supervisor.subscribe(lambda e: usage.append(e) if isinstance(e, Resources)
                                     else None)
            await until(pilot, lambda: len(ticks(app)) >= 3)
            assert "[robot1:far]" in str(app.status_bar.render())
            # the first may have come before (a loaded machine draws the first frame late):
            # a process selected, its figures are sent
            tree = app.launch_tree
            tree.move_cursor(tree.rows["ticker-1"])
            await until(pilot, lambda: any("ticker-1" in (e.data or {}) for e in usage))
            for pid in proxies_on(robot):
                os.kill(pid, signal.SIGKILL)  # the link dies; ssh ends with it
            await until(pilot, lambda: "link to robot1 lost" in str(app.status_bar.render()))
            usage.clear()  # nothing comes while the link is down
            seen = len(ticks(app))
            # meanwhile, over there: lines go on, and another operator restarts a node
            restarted = run_cli("restart", "robot1:far", "quiet")
            assert restarted.returncode == 0, restarted.stderr
            await pilot.pause(1.0)
            assert len(ticks(app)) == seen  # nothing arrives while the link is down
            # the time column, whose stamps cannot be read now: shown all the same
            await pilot.press("T")
            await until(pilot, lambda: any(
                re.match(r"\d\d:\d\d:\d\d\.\d{3} .*tick \d+$", row)
                for row in app.output_panel.line_view.visible_text()))
            await pilot.press("R")
            await until(pilot, lambda: "link to robot1 lost" not in str(
                app.status_bar.render()) and len(ticks(app)) > seen + 5)
            shown = ticks(app)
            assert shown == [f"tick {i}" for i in range(1, len(shown) + 1)]
            # the watch ended with the old connection; the new one asked again
            await until(pilot, lambda: usage)
            quiet = [line.text for line in app.store.lines(View("quiet-2"))]
            assert sum("process started with pid" in t for t in quiet) == 2
            assert app.supervisor is not None
            assert app.supervisor.states["quiet-2"] == "running"
            # new lines keep coming on the new link
            now = len(ticks(app))
            await until(pilot, lambda: len(ticks(app)) > now + 3)
            shown = ticks(app)
            assert shown == [f"tick {i}" for i in range(1, len(shown) + 1)]
            # the ssh client killed this time, and no R: it reconnects by itself
            monkeypatch.setattr(remote_supervisor, "RETRY_FIRST", 1.0)
            assert app.supervisor.link is not None
            app.supervisor.link.process.kill()
            await until(pilot, lambda: "link to robot1 lost" in str(app.status_bar.render()))
            seen = len(ticks(app))
            await until(pilot, lambda: "link to robot1 lost" not in str(
                app.status_bar.render()) and len(ticks(app)) > seen + 3)
            shown = ticks(app)
            assert shown == [f"tick {i}" for i in range(1, len(shown) + 1)]
            # quitting asks; "d" detaches, the launch running on there
            await pilot.press("q")
            await until(pilot, lambda: isinstance(app.screen, QuitScreen))
            await pilot.press("d")
            await until(pilot, lambda: app.detached)
        assert app.detached

    asyncio.run(attached())
    after = json.loads(run_cli("status", "robot1:far", "--json").stdout)
    assert after["pid"] == server
    assert {p["id"]: p["state"] for p in after["processes"]} == {
        "ticker-1": "running", "quiet-2": "running"}
    assert {p["id"]: p["pid"] for p in after["processes"]}["ticker-1"] == before["ticker-1"]
    assert run_cli("stop", "robot1:far").returncode == 0
    wait_for(lambda: not alive(server))
    assert proxies_on(robot) == []


ARGUED = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
from launch.substitutions import LaunchConfiguration
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('nap', default_value='600', description='how long quiet sleeps'),
        ExecuteProcess(name='ticker', cmd=[
            'sh', '-c', 'i=0; while true; do i=$((i+1)); echo tick $i; sleep 0.2; done']),
        ExecuteProcess(name='quiet', cmd=['sleep', LaunchConfiguration('nap')]),
    ])
"""


def test_attach_without_the_launch_file_here_draws_the_servers_plan(machines: Machines,
                                                                    tmp_path, monkeypatch):
    """The launch file is on the robot only: the tree, the output and the argument form
    come from robot1's server, and an argument edit is previewed and applied there."""
    robot = machines["robot1"]
    files = tmp_path / "on-robot1"
    files.mkdir()
    path = files / "argued_launch.py"
    path.write_text(ARGUED)
    with logged_in(robot):
        start_here(path, "--name", "far")
        wait_state("far", "quiet-2", "running")
    status = status_there(robot, "far")
    quiet_pid = {p["id"]: p["pid"] for p in status["processes"]}["quiet-2"]
    files.rename(tmp_path / "moved-away")  # not readable here at that path any more
    elsewhere = tmp_path / "operator"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)

    async def attached() -> None:
        app = make_app(status["file"], status["arguments"], Path(status["log_dir"]),
                       session_name="far", session_host="robot1")
        # robot1 shares this filesystem: the file goes back where its server reads it
        # again at each relaunch, the client having chosen to draw the server's plan
        (tmp_path / "moved-away").rename(files)
        async with app.run_test(size=(100, 30)) as pilot:
            await until(pilot, lambda: any(line.text.startswith("tick") for line in
                                           app.store.lines(View("ticker-1"))))
            assert set(app.launch_tree.states) >= {"ticker-1", "quiet-2"}
            assert [p.id for p in app.session.plan.processes] == ["ticker-1", "quiet-2"]
            await pilot.press("2")
            field = app.query_one("#arg-nap", Input)
            assert field.value == "600"
            field.value = "601"
            await pilot.pause()
            preview = app.query_one("#args-preview")
            assert "would restart: quiet-2" in str(preview.render())
            await pilot.press("f5")
            await until(pilot, lambda: "Applied." in str(preview.render()))
            assert app.session.arguments == {"nap": "601"}
            app.leaving.detach()  # "d" would be typed into the focused field
            await until(pilot, lambda: app.detached)

    asyncio.run(attached())
    after = json.loads(run_cli("status", "robot1:far", "--json").stdout)
    assert after["arguments"] == {"nap": "601"}
    quiet = {p["id"]: p for p in after["processes"]}["quiet-2"]
    assert quiet["pid"] != quiet_pid and quiet["state"] == "running"
    assert run_cli("stop", "robot1:far").returncode == 0


def test_attach_on_a_terminal_and_logs_follow_through_the_link(machines: Machines, write):
    server = start_on(machines["robot1"], write, "far")
    terminal = Terminal("attach", "robot1:far")
    try:
        terminal.read_until(b"[robot1:far]")  # the status line names the session's machine
        terminal.read_until(b"tick")  # the remote node's output, on this screen
        os.write(terminal.master, b"d")
        assert terminal.wait_exit() == 0
        assert b"detached; session robot1:far runs on" in terminal.screen
    finally:
        terminal.close()
    assert alive(server)

    # the lines in the file by now: -f prints them, then live ones
    logged = len(run_cli("logs", "robot1:far", "ticker-1").stdout.splitlines())
    follow = subprocess.Popen([sys.executable, "-m", "tuilaunch", "logs", "robot1:far",
                               "ticker-1", "-f"], stdout=subprocess.PIPE, text=True,
                              start_new_session=True)
    try:
        assert follow.stdout is not None
        lines = []
        for line in follow.stdout:  # the file's lines, then the live ones, no gap
            lines.append(line.rstrip("\n"))
            if len(lines) >= logged + 5:
                break
        assert lines[0].startswith("[INFO] [ticker-1]: process started with pid [")
        assert lines[1:] == [f"tick {i}" for i in range(1, len(lines))]
    finally:
        os.killpg(follow.pid, signal.SIGTERM)
        follow.wait()
    table = run_cli("ls", "robot1")
    assert table.returncode == 0 and "far" in table.stdout and "2/2" in table.stdout


def test_a_tui_whose_link_fails_before_it_mounts_exits_with_the_reason(machines, write,
                                                                       tmp_path):
    app = make_app(str(write(LAUNCH)), {}, tmp_path, session_name="nothere",
                   session_host="robot1")

    async def attach() -> None:
        async with app.run_test(size=(80, 24)) as pilot:
            await pilot.pause(0.1)

    asyncio.run(attach())
    assert app.return_code == 2
    assert app.supervisor is None


def test_a_fair_buffer_drops_the_loudest_process_lines_not_the_oldest():
    """A display sent a screenful a second (over a link) still sees a quiet node's line
    beside a flood; the unfair buffer (a local display's) keeps only the newest."""
    for fair, quiet_kept in ((True, ["hello"]), (False, [])):
        buffer = EventBuffer(max_lines=10, fair=fair)
        buffer(Output("quiet", lines=["hello"]))
        for i in range(50):
            buffer(Output("loud", lines=[f"x{i}"]))
        events = buffer.drain()
        kept = {name: [text for e in events if e.kind == "output" and e.process == name
                       for text in e.lines] for name in ("quiet", "loud")}
        assert kept["quiet"] == quiet_kept
        assert kept["loud"] == [f"x{i}" for i in range(50 - 10 + len(quiet_kept), 50)]
        dropped = {e.process: e.code for e in events if e.kind == "dropped"}
        assert dropped.get("loud") == 40 + len(quiet_kept)


def test_a_batch_carries_each_run_of_a_process_lines_once():
    """Reads of one pipe in a row are one event in a batch (one header over the link), in
    order; another process's output or a state event between them keeps them apart."""
    buffer = EventBuffer()
    buffer(Output("a", stream="stdout", lines=["1"]))
    buffer(Output("a", stream="stdout", lines=["2", "3"]))
    buffer(Output("a", stream="stderr", lines=["oops"]))
    buffer(Output("b", stream="stdout", lines=["b1"]))
    buffer(Event("exited", "b", code=0))
    buffer(Output("a", stream="stderr", lines=["again"]))
    events = buffer.drain()
    assert [(e.kind, e.process, e.stream, e.lines) for e in events] == [
        ("output", "a", "stdout", ["1", "2", "3"]), ("output", "a", "stderr", ["oops"]),
        ("output", "b", "stdout", ["b1"]), ("exited", "b", None, []),
        ("output", "a", "stderr", ["again"])]


def test_a_display_gets_lines_as_it_shows_them_and_stamps_to_the_millisecond():
    """Over a link a display's lines come without colour codes and with their ROS stamp to
    the millisecond (the pane's time column), sent apart as differences: what it shows
    is restored exactly, whatever the order of the stamps and the lines without one."""
    from tuilaunch.engine.run.session.clients import shown_line
    from tuilaunch.engine.run.session.protocol import Stamps, decode, encode

    raw = ["\x1b[0m[INFO] [1795636064.475123456] [r1.talker]: hi 1\x1b[0m",
           "a plain line [1795636064.475]",
           "[WARN] [1795636064.470999999] [r1.talker]: earlier",
           "[ERROR] [1795636065.001000000] [r1.x]: later"]
    shown = [shown_line(line) for line in raw]
    assert shown == ["[INFO] [1795636064.475] [r1.talker]: hi 1",
                     "a plain line [1795636064.475]",
                     "[WARN] [1795636064.470] [r1.talker]: earlier",
                     "[ERROR] [1795636065.001] [r1.x]: later"]
    sent = [{"kind": "output", "process": "p", "lines": shown[:2]},
            {"kind": "output", "process": "q", "lines": shown[2:]}]
    packer = Stamps()
    for data in sent:
        packer.pack(data)
    wire = decode(encode({"type": "events", "events": sent}))
    assert all("1795636064" not in line for e in wire["events"] for line in e["lines"]
               if line.startswith("["))
    unpacker = Stamps()
    for data in wire["events"]:
        unpacker.unpack(data)
    assert [line for e in wire["events"] for line in e["lines"]] == shown


STAMPED = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(name='logger', cmd=['sh', '-c', 'i=0; while true; do '
        'i=$((i+1)); printf "[INFO] [%d.%03d123456] [far.logger]: line %d\\\\n" '
        '$((1700000000+i)) $((i%1000)) $i; sleep 0.1; done']))
    return sl.launch_description()
"""


def printed(number: int) -> str:
    """The logger's line `number` as the pane's raw format shows it (stamp to the ms)."""
    return f"[INFO] [{1700000000 + number}.{number % 1000:03d}] [far.logger]: line {number}"


def clock(number: int) -> str:
    """The time column of the logger's line `number`: its ROS stamp, not its arrival."""
    return time.strftime("%H:%M:%S", time.localtime(1700000000 + number)) + \
        f".{number % 1000:03d}"


def test_over_a_link_the_stamps_come_when_the_time_column_shows_them(machines: Machines,
                                                                       write, monkeypatch,
                                                                       tmp_path):
    """A TUI over ssh is not sent the ROS stamps its pane does not show: `T` (the time
    column) reads them for the lines it holds and has the next lines sent with them, `f`
    (the line as printed) the same, and a saved pane has every line as printed; turned off,
    the lines come without them again. Every line once, in order, with its own stamp. `w`
    writes the pane on this computer, not in the log folder over there, where its notice
    says."""
    robot = machines["robot1"]
    # the pane saved here (its log folder is over there): in this test's folder, where no
    # earlier run's saves are
    monkeypatch.setenv("ROS_LOG_DIR", str(tmp_path / "here"))
    path = write(STAMPED)
    with logged_in(robot):
        start_here(path, "--name", "stamped")
        wait_state("stamped", "logger-1", "running")
    status = status_there(robot, "stamped")

    def held(app) -> list[tuple[int, str]]:
        return [(int(line.text.rsplit(" ", 1)[1]), line.text)
                for line in app.store.lines(View("logger-1")) if "line " in line.text]

    def rows(app) -> list[str]:
        """The logger's rows on screen (the all-nodes pane: without the process's name)."""
        return [row.replace("logger-1 ", "", 1)
                for row in app.output_panel.line_view.visible_text() if "line " in row]

    def numbered(row: str) -> int:
        return int(row.rsplit(" ", 1)[1])

    async def attached() -> None:
        app = make_app(status["file"], status["arguments"], Path(status["log_dir"]),
                       session_name="stamped", session_host="robot1")
        async with app.run_test(size=(100, 30)) as pilot:
            # the lines since the attach came without their stamp (the replay, read from
            # the log file over there, has them)
            await until(pilot, lambda: sum("[1700" not in t for _, t in held(app)) >= 5)
            await pilot.press("T")
            await until(pilot, lambda: len(rows(app)) >= 10 and all(
                row.startswith(clock(numbered(row)) + " I line ") for row in rows(app)))
            # from here the lines come with their stamps
            seen = max(n for n, _ in held(app))
            await until(pilot, lambda: max(n for n, _ in held(app)) > seen + 10)
            assert all(text == printed(n) for n, text in held(app) if n > seen)
            await pilot.press("T", "f")
            await until(pilot, lambda: rows(app) and all(
                row == printed(numbered(row)) for row in rows(app)))
            # both off: the link leaves the stamps out again; a save reads them first
            await pilot.press("f")
            seen = max(n for n, _ in held(app))
            await until(pilot, lambda: sum("[1700" not in t for n, t in held(app)
                                           if n > seen) >= 5)
            assert all(row.startswith("I line ") for row in rows(app))
            await pilot.press("w")
            # written on this computer (the log folder is over there), where the notice says
            saved = pane_save_dir(app.log_dir, app.session_host, app.session_name)
            await until(pilot, lambda: list(saved.glob("*-pane-*.txt")))
            await until(pilot, lambda: any("pane saved to" in n.message
                                           for n in app._notifications))
            said = next(n.message for n in app._notifications if "pane saved to" in n.message)
            path = Path(said.split("pane saved to ", 1)[1])
            assert path.is_relative_to(tmp_path / "here" / "tuilaunch-robot1-stamped"), path
            assert not str(path).startswith(status["log_dir"])
            assert [path] == list(saved.glob("*-pane-*.txt"))
            lines = [line for line in path.read_text().splitlines() if "line " in line]
            numbers = [numbered(line) for line in lines]
            assert numbers == list(range(numbers[0], numbers[0] + len(numbers)))
            assert numbers[-1] > seen + 4
            # the lines replayed from the log file on attaching have the nanoseconds
            assert all(line in (f"[logger-1] {printed(n)}",
                                f"[logger-1] {printed(n).replace('] [far', '123456] [far')}")
                       for line, n in zip(lines, numbers, strict=True))
            await pilot.press("q")
            await until(pilot, lambda: isinstance(app.screen, QuitScreen))
            await pilot.press("d")
            await until(pilot, lambda: app.detached)

    asyncio.run(attached())
    assert run_cli("stop", "robot1:stamped").returncode == 0


STREAMED = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(name='ticker', cmd=[
        'sh', '-c', 'i=0; while true; do i=$((i+1)); echo tick $i; sleep 0.2; done']))
    sl.node('tuilaunch_demos', 'talker', name='talker', parameters=[{'rate': 10.0}])
    return sl.launch_description()
"""


class Streaming:
    """A streaming command (`logs -f`, `hz`, `wait`) through the link, read as it comes."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", *args],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True, start_new_session=True)

    def read_until(self, text: str) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            if text in line:
                return
        raise AssertionError(f"never printed {text!r}: {self.proc.stderr.read()}")

    def ssh(self) -> list[int]:
        """Its ssh (this side of the link)."""
        from .proc_tree import cmdline, descendants

        return [pid for pid in descendants(self.proc.pid) if b"__proxy" in cmdline(pid)]

    def ended(self) -> tuple[int, str]:
        try:
            self.proc.wait(timeout=60)
        finally:
            if self.proc.poll() is None:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        assert self.proc.stderr is not None
        return self.proc.returncode, self.proc.stderr.read()


def test_a_stream_whose_link_drops_says_so_and_the_session_runs_on(machines: Machines,
                                                                   write):
    """`logs -f` and `hz` over ssh: the link's end is not the session's (exit 1 and
    one line naming the host, not exit 0 or "session ended")."""
    robot1 = machines["robot1"]
    with logged_in(robot1):
        start_here(write(STREAMED), "--name", "far")
        wait_state("far", "talker-2", "running")
    server = int(status_there(robot1, "far")["pid"])
    lost = re.compile(r"^tuilaunch (logs|hz): link to robot1 lost: \S.*\n\Z")

    # the proxy on robot1 dies (the far end of the link)
    follow = Streaming("logs", "robot1:far", "ticker-1", "-f")
    follow.read_until("tick")
    wait_for(lambda: len(proxies_on(robot1)) == 1)
    for pid in proxies_on(robot1):
        os.kill(pid, signal.SIGKILL)
    code, said = follow.ended()
    assert code == 1 and lost.match(said), (code, said)

    # this side's ssh dies
    rate = Streaming("hz", "robot1:far", "/chatter")
    rate.read_until("average rate")
    for pid in rate.ssh():
        os.kill(pid, signal.SIGKILL)
    code, said = rate.ended()
    assert code == 1 and lost.match(said), (code, said)

    # the session ran on through all of it
    assert alive(server)
    status = json.loads(run_cli("status", "robot1:far", "--json").stdout)
    assert {p["id"]: p["state"] for p in status["processes"]} == {
        "ticker-1": "running", "talker-2": "running"}
    # and a session that does end is still told apart: exit 2, "session robot1:far ended"
    # (the session named as typed, e875fad)
    rate = Streaming("hz", "robot1:far", "/chatter")
    rate.read_until("average rate")
    assert run_cli("stop", "robot1:far").returncode == 0
    code, said = rate.ended()
    assert code == 2 and "session robot1:far ended" in said, (code, said)


def status_row(app) -> str:
    """The status line as the terminal shows it (cut at the screen's width)."""
    return app.status_bar.render_line(0).text


def test_a_lost_link_fits_80_columns_says_each_attempt_and_a_hung_link_its_silence(
        machines: Machines, write, monkeypatch):
    """At 80x24: "link to robot1 lost · reconnecting · far" whole; the reason is the latest
    attempt's; a link that hangs (no bytes, no error) shows how long it has been silent."""
    robot = machines["robot1"]
    start_on(robot, write, "far")
    status = status_there(robot, "far")
    monkeypatch.setattr(remote_supervisor, "RETRY_FIRST", 600.0)  # only R reconnects
    # the silence said after 2.5 s, not 5: still past the probe (remote_supervisor's
    # PROBE_AFTER), which a hung link leaves unanswered
    monkeypatch.setattr(status_line, "SILENCE_SHOWN", remote_supervisor.PROBE_AFTER + 0.5)
    config = machines.ssh_config.read_text()

    async def attached() -> None:
        app = make_app(status["file"], status["arguments"], Path(status["log_dir"]),
                       session_name="far", session_host="robot1")
        async with app.run_test(size=(80, 24)) as pilot:
            await until(pilot, lambda: "[robot1:far]" in status_row(app))
            for pid in proxies_on(robot):
                os.kill(pid, signal.SIGKILL)
            await until(pilot, lambda: "link to robot1 lost" in status_row(app))
            assert status_row(app).startswith("link to robot1 lost · reconnecting · far · "
                                              "R: now · "), status_row(app)
            # robot1 off the network now: the next attempt's reason replaces the first
            machines.ssh_config.write_text(config.replace(
                f"Port {robot.port}\n", f"Port {free_port()}\n"))
            await pilot.press("R")
            await until(pilot, lambda: "Connection refused" in str(app.status_bar.render()))
            # the reason's end fits the line (its whole is in the launch pane)
            assert status_row(app).startswith("link to robot1 lost · reconnecting · far · "
                                              "R: now · … Connection refused"), status_row(app)
            machines.ssh_config.write_text(config)
            await pilot.press("R")
            await until(pilot, lambda: "[robot1:far]" in status_row(app))
            # a hung link: the proxy there stopped, ssh sees no error for 15 s
            await until(pilot, lambda: len(proxies_on(robot)) == 1)
            hung = proxies_on(robot)[0]
            os.kill(hung, signal.SIGSTOP)
            try:
                await until(pilot, lambda: re.match(r"no word from robot1 for \d+ s · ",
                                                    status_row(app)) is not None)
            finally:
                os.kill(hung, signal.SIGCONT)
            await until(pilot, lambda: "no word" not in status_row(app))
            await pilot.press("d")
            await until(pilot, lambda: app.detached)

    asyncio.run(attached())
    assert run_cli("stop", "robot1:far").returncode == 0


def test_a_server_killed_there_is_its_end_not_a_lost_link(machines: Machines, write):
    """`kill -9` of the session's server on robot1, the link up all along: said as the
    session's end (no "while the link was down", no reconnecting), by `logs -f` too."""
    robot = machines["robot1"]
    server = start_on(robot, write, "far")
    status = status_there(robot, "far")
    follow = Streaming("logs", "robot1:far", "ticker-1", "-f")
    follow.read_until("tick")
    said: list[str] = []

    async def attached() -> None:
        app = make_app(status["file"], status["arguments"], Path(status["log_dir"]),
                       session_name="far", session_host="robot1")
        async with app.run_test(size=(100, 30)) as pilot:
            await until(pilot, lambda: any(line.text.startswith("tick") for line in
                                           app.store.lines(View("ticker-1"))))
            assert app.supervisor is not None
            app.supervisor.subscribe(lambda e: said.append(e.reason or "")
                                     if e.kind == "log" else None)
            os.kill(server, signal.SIGKILL)
            await until(pilot, lambda: any("ended without a word" in s for s in said))
            assert "link to robot1 lost" not in str(app.status_bar.render())

    asyncio.run(attached())
    gone = f"robot1: session far ended without a word: its server (pid {server}) is gone"
    assert gone in said, said
    assert not any("while the link was down" in s or "reconnecting" in s for s in said), said
    code, stderr = follow.ended()
    assert code == 2 and f"tuilaunch logs: error: {gone}" in stderr, (code, stderr)


def test_a_remote_command_that_is_no_tuilaunch_is_named_with_its_host(machines: Machines):
    """`TUILAUNCH_REMOTE=/bin/true`: it exits 0 without a word of the protocol; said so,
    naming the command and the host, not "failed: exit status 0"."""
    done = run_cli("status", "robot1:far", env={"TUILAUNCH_REMOTE": "/bin/true"})
    assert done.returncode == 2
    assert done.stderr.startswith(
        "tuilaunch status: error: robot1: the remote command '/bin/true' exited without "
        "speaking the session protocol (exit status 0)\n"), done.stderr
    assert "hint: is /bin/true a tuilaunch? (TUILAUNCH_REMOTE names it)" in done.stderr


UNNAMED = """
from launch import LaunchDescription
from launch_ros.actions import Node
def generate_launch_description():
    return LaunchDescription([Node(package='tuilaunch_demos', executable='talker',
                                   namespace='r2', parameters=[{'rate': 5.0}])])
"""


def test_a_restart_at_debug_level_over_ssh_keeps_the_node_name(machines: Machines, write):
    """Over ssh as here: after `restart --log-level debug` rcl's lines come first, and the
    node is still known by its own name (issue 36, item 4)."""
    robot = machines["robot1"]
    with logged_in(robot):
        start_here(write(UNNAMED), "--name", "far")
    try:
        def dumped() -> bool:
            return "rate:" in run_cli("params", "robot1:far", "talker-1", "--dump").stdout

        wait_for(dumped)
        restarted = run_cli("restart", "robot1:far", "talker-1", "--log-level", "debug")
        assert restarted.returncode == 0, restarted.stderr
        wait_for(lambda: "[rcl]: " in run_cli("logs", "robot1:far", "talker-1").stdout)
        wait_for(dumped)
    finally:
        assert run_cli("stop", "robot1:far").returncode == 0
