"""Nodes placed on machines (`--machines`), over real sshd "machines" (tests/integration/sshd.py).

The launching side is this test's own session folder; "robot1" runs its share as a
session in its own folder, reached only through ssh. The remote tuilaunch is a small
wrapper (the machine's `tuilaunch:` field): the CLI for a share, the proxy module for the
link, until the CLI's own hidden `__proxy` arrives.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from tuilaunch.engine.run.session import session_dir
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.engine.run.vocabulary.requests import Apply
from tuilaunch.tui.app import TuiLaunchApp, make_app

from ..conftest import run_cli, wait_for
from .proc_tree import cmdline, descendants
from .sshd import Machine, Machines, alive, free_port, keygen, machines_fixture  # noqa: F401
from .test_sessions import status
from .test_tui import until

LAUNCH = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess, LogInfo, RegisterEventHandler
from launch.event_handlers import OnProcessIO, OnProcessStart
def generate_launch_description():
    far = ExecuteProcess(name='far', cmd=['sh', '-c',
        'echo far up; i=0; while true; do i=$((i+1)); echo far tick $i; sleep 0.2; done'])
    solo = ExecuteProcess(name='solo', cmd=['sh', '-c',
        'echo solo up; while true; do sleep 0.5; done'])
    near = ExecuteProcess(name='near', cmd=['sh', '-c',
        'echo near up; while true; do sleep 0.5; done'])
    return LaunchDescription([far, solo, RegisterEventHandler(
        OnProcessStart(target_action=far, on_start=[near])), RegisterEventHandler(
        OnProcessIO(target_action=far, on_stdout=lambda event: LogInfo(
            msg='heard ' + event.text.decode().strip())))])
"""


def remote_tuilaunch(folder: Path) -> Path:
    """The machines' `tuilaunch:`: the CLI, whose hidden proxy commands come from the proxy
    module for now."""
    script = folder / "tl"
    script.write_text(
        "#!/bin/sh\n"
        'case "$1" in __proxy|__ls) exec "' + sys.executable + '" -m '
        'tuilaunch.engine.run.machines.proxy "$@";; esac\n'
        'exec "' + sys.executable + '" -m tuilaunch "$@"\n')
    script.chmod(0o755)
    return script


@pytest.fixture(name="setup")
def setup_fixture(machines: Machines, tmp_path: Path, write,
                  monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[Path, Path]]:
    """The launch file and a machines file placing `far` on robot1 (as r1) and on an
    unreachable robot3 (as r3, when asked by the test's own file)."""
    monkeypatch.setenv("ROS_LOG_DIR", str(tmp_path / "log"))
    # the launching side's own session folder (short: a socket path has 108 bytes at most)
    runtime = Path(tempfile.mkdtemp(prefix="tlhere"))
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime))
    launch = write(LAUNCH)
    dead_port = free_port()  # nothing listens there: a machine that is off
    with open(machines.ssh_config, "a") as config:
        config.write(machines.host_entry("robot3", dead_port))
    tool = remote_tuilaunch(tmp_path)
    placement = tmp_path / "machines.yaml"
    placement.write_text(
        "machines:\n"
        f"  r1: {{host: robot1, tuilaunch: {tool}}}\n"
        f"  r3: {{host: robot3, tuilaunch: {tool}}}\n"
        "placement:\n"
        "  - {match: far-*, machine: r1}\n")
    try:
        yield launch, placement
    finally:
        # a launching-side session a failed test left running is stopped (it stops its
        # shares); the machines' own teardown ends whatever is left there
        servers = [json.loads(info.read_text())["pid"]
                   for info in (runtime / "tuilaunch").glob("*.json")]
        for pid in servers:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGTERM)
        with contextlib.suppress(AssertionError):
            wait_for(lambda: not any(alive(pid) for pid in servers), 60)
        for pid in servers:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(runtime, ignore_errors=True)


def remote_sessions(machines: Machines, alias: str) -> list[dict]:
    """The sessions running on `alias`, each as `status --json` there says it (its name,
    arguments, ...), as `tuilaunch ls` there finds them; one that ends meanwhile is not
    listed. Read from this process: the tests look often, and a command costs a quarter
    of a second of CPU."""
    found = []
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("XDG_RUNTIME_DIR", str(machines[alias].runtime))
        for name in session_dir.live_sessions():
            try:
                found.append(status(name))
            except SessionError:
                continue
    return found


class Headless:
    """`tuilaunch FILE --machines M --headless`, its output read as it comes."""

    def __init__(self, *args: str) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "tuilaunch", *args, "--headless"], stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT, env=os.environ.copy())
        self.chunks: list[bytes] = []
        self.reader = threading.Thread(target=self._pump, daemon=True)
        self.reader.start()

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        while chunk := os.read(self.proc.stdout.fileno(), 65536):
            self.chunks.append(chunk)

    @property
    def text(self) -> str:
        return b"".join(self.chunks).decode(errors="replace")

    def read(self) -> str:
        return self.text

    def wait_for(self, pattern: str, limit: float = 90.0) -> re.Match[str]:
        found: list[re.Match[str]] = []

        def check() -> bool:
            match = re.search(pattern, self.read())
            if match:
                found.append(match)
            return match is not None

        try:
            wait_for(check, limit)
        except AssertionError:
            raise AssertionError(f"never printed {pattern!r}:\n{self.text}") from None
        return found[0]

    def __enter__(self) -> Headless:
        return self

    def __exit__(self, *_: object) -> None:
        """Whatever the test did: tuilaunch does not outlive it."""
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()

    def stop(self) -> int:
        self.proc.send_signal(signal.SIGINT)
        try:
            code = self.proc.wait(timeout=90)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()
        self.reader.join(timeout=10)
        return code


def test_print_shows_where_each_process_runs(setup) -> None:
    launch, placement = setup
    printed = run_cli(str(launch), "--machines", str(placement), "--print")
    assert printed.returncode == 0, printed.stderr
    assert "[far-1] @r1" in printed.stdout
    assert "here: solo-2, near-3" in printed.stdout
    assert "r1 (robot1): far-1" in printed.stdout
    plan = json.loads(run_cli(str(launch), "--machines", str(placement), "--print",
                              "--json").stdout)
    assert {p["id"]: p["machine"] for p in plan["processes"]} == {
        "far-1": "r1", "solo-2": None, "near-3": None}
    # a rule that places nothing is said (a typo in a name would otherwise go unseen)
    placement.write_text(placement.read_text() + "  - {match: /nobody/**, machine: r1}\n")
    printed = run_cli(str(launch), "--machines", str(placement), "--print")
    assert "placement rule '/nobody/**' -> r1 places no process" in printed.stdout


def test_a_node_on_robot1_runs_there_shows_here_starts_a_node_here_and_outlives_its_link(
        setup, machines):
    launch, placement = setup
    with Headless(str(launch), "--machines", str(placement)) as run:
        started = run.wait_for(r"\[INFO\] \[far-1@r1\]: process started with pid \[(\d+)\]")
        far_pid = int(started.group(1))
        run.wait_for(r"\[far-1@r1\] far tick")  # its output, labelled with its machine
        # an OnProcessIO handler here hears it
        run.wait_for(r"\[INFO\] \[[^\]]+\]: heard far tick 3\n")
        # what it printed before the link was made is shown too, first
        assert run.text.index("[far-1@r1] far up") < run.text.index("[far-1@r1] far tick 1\n")
        # near-2 waits for far-1's start, which happened on robot1
        run.wait_for(r"\[INFO\] \[near-3\]: process started")
        assert run.text.index("[far-1@r1]: process started") < \
            run.text.index("[near-3]: process started")
        shares = remote_sessions(machines, "robot1")
        assert len(shares) == 1 and shares[0]["name"].endswith("-r1")
        assert alive(far_pid)  # a process of robot1's share (same pid space here)

        # a dropped link stops nothing and is made again
        links = [pid for pid in descendants(run.proc.pid) if b"__proxy" in cmdline(pid)]
        assert links, "no ssh link to robot1's share"
        for pid in links:
            os.kill(pid, signal.SIGKILL)  # the link dies as a cable pulled out would
        lost = run.wait_for(r"\[WARN\] \[launch.user\]: r1: (.*); its share runs on there; "
                            r"connecting again in 1 s")
        assert "lost the link to robot1" in lost.group(1)
        assert alive(far_pid)  # the share ran on
        after = len(run.text)
        wait_for(lambda: "r1: following session" in run.text[after:] and
                 "[far-1@r1] far tick" in run.text[after:].split("following session", 1)[-1])
        code = run.stop()
    # stopping the launch stopped everything on robot1
    assert code == 0, run.text
    assert "[INFO] [far-1@r1]: process stopped" in run.text
    assert not alive(far_pid)
    wait_for(lambda: remote_sessions(machines, "robot1") == [])
    # what it printed while the link was down was shown once it was back: no gap, no twice
    ticks = [int(n) for n in re.findall(r"\[far-1@r1\] far tick (\d+)\n", run.text)]
    assert ticks == list(range(1, len(ticks) + 1)), ticks


def test_status_on_the_launching_side_shows_each_process_and_its_machine(setup, machines):
    launch, placement = setup
    name = "placed"
    done = run_cli(str(launch), "--machines", str(placement), "--detach", "--name", name)
    assert done.returncode == 0, done.stderr
    try:
        waited = run_cli("wait", name, "far-1", "running", "--timeout", "60", timeout=90)
        assert waited.returncode == 0, waited.stderr
        waited = run_cli("wait", name, "near-3", "running", "--timeout", "60", timeout=90)
        assert waited.returncode == 0, waited.stderr
        status = json.loads(run_cli("status", name, "--json").stdout)
        rows = {p["id"]: p for p in status["processes"]}
        assert rows["far-1"]["machine"] == "r1" and rows["far-1"]["state"] == "running"
        assert rows["solo-2"]["machine"] is None and rows["solo-2"]["state"] == "running"
        table = run_cli("status", name).stdout
        assert re.search(r"^  far-1@r1 +running ", table, re.M), table
        # its output is in the log files here too (`tuilaunch logs` on the launching side)
        wait_for(lambda: "far tick" in run_cli("logs", name, "far-1").stdout)
        # the TUI attached here shows it in the one tree, labelled with its machine
        asyncio.run(attached_tree_shows_machine(name, status))
        # a restart of a process placed there is done there
        far_pid = rows["far-1"]["pid"]
        restarted = run_cli("restart", name, "far-1", timeout=90)
        assert restarted.returncode == 0, restarted.stderr
        wait_for(lambda: not alive(far_pid))
        # the share's own view: it runs far-1, the others are elsewhere
        share = remote_sessions(machines, "robot1")[0]["name"]
        there = run_cli("status", share, "--json",
                        env={"XDG_RUNTIME_DIR": str(machines["robot1"].runtime)})
        states = {p["id"]: p["state"] for p in json.loads(there.stdout)["processes"]}
        assert states == {"far-1": "running", "solo-2": "elsewhere", "near-3": "elsewhere"}
        # under a tool (`g` in the TUI): robot1 runs it so, and a wait right after the
        # restart is for the new run, not the end of the old one
        restarted = run_cli("restart", name, "far-1", "--prefix", "env TL_FAR=1", timeout=90)
        assert restarted.returncode == 0, restarted.stderr
        waited = run_cli("wait", name, "far-1", "running", "--timeout", "60", timeout=90)
        assert waited.returncode == 0, waited.stderr
        there = run_cli("status", share, "--json",
                        env={"XDG_RUNTIME_DIR": str(machines["robot1"].runtime)})
        far = next(p for p in json.loads(there.stdout)["processes"] if p["id"] == "far-1")
        assert far["command"][:2] == ["env", "TL_FAR=1"] and far["state"] == "running"
        # a tool robot1 does not have: said, and far-1 runs on as it was
        refused = run_cli("restart", name, "far-1", "--prefix", "no-such-debugger",
                          timeout=90)
        assert refused.returncode != 0
        assert "r1" in refused.stderr and "no-such-debugger" in refused.stderr, refused.stderr
        assert "Traceback" not in refused.stderr
        there = run_cli("status", share, "--json",
                        env={"XDG_RUNTIME_DIR": str(machines["robot1"].runtime)})
        again = next(p for p in json.loads(there.stdout)["processes"] if p["id"] == "far-1")
        assert again["pid"] == far["pid"] and again["state"] == "running"
    finally:
        stopped = run_cli("stop", name, timeout=120)
    assert stopped.returncode == 0, stopped.stderr
    wait_for(lambda: remote_sessions(machines, "robot1") == [])


def placed_app(name: str, status: dict) -> TuiLaunchApp:
    """`tuilaunch attach NAME` of a placed session (`status`: its `status --json`): the tree
    labels each process with its machine."""
    from tuilaunch.engine.plan.machines import placement_from_text

    placed = status["placement"]
    return make_app(status["file"], status["arguments"], Path(status["log_dir"]),
                    session_name=name, placement=placement_from_text(placed["text"],
                                                                     placed["path"]))


async def attached_tree_shows_machine(name: str, status: dict) -> None:
    from tuilaunch.tui.output_store import View

    app = placed_app(name, status)
    async with app.run_test(size=(120, 30)) as pilot:
        assert app.supervisor is not None
        for _ in range(400):
            far = str(app.launch_tree.rows["far-1"].label)
            ticks = [line.text for line in app.store.lines(View("far-1"))
                     if "far tick" in line.text]
            if "running" in far and len(ticks) > 2:
                break
            await pilot.pause(0.05)
        assert "@r1" in far and "running" in far, far
        assert "@" not in str(app.launch_tree.rows["solo-2"].label)
        assert len(ticks) > 2
        await pilot.press("d")  # detach: the launch runs on
        await until(pilot, lambda: app.detached)
    assert app.detached


def test_an_unreachable_machine_fails_its_nodes_in_one_line_and_the_rest_runs(setup):
    launch, placement = setup
    placement.write_text(placement.read_text().replace("machine: r1", "machine: r3"))
    with Headless(str(launch), "--machines", str(placement)) as run:
        failed = run.wait_for(r"\[ERROR\] \[far-1@r3\]: failed to start: (.*)\n")
        assert re.fullmatch(r"cannot reach r3 \(robot3\): .*Connection refused",
                            failed.group(1)), failed.group(1)
        run.wait_for(r"\[solo-2\] solo up")
        code = run.stop()
    assert code != 0
    assert "[near-3]: process started" not in run.text  # what it waits for never started


def test_a_node_on_robot1_waits_for_a_node_here(setup, machines):
    launch, placement = setup
    placement.write_text(placement.read_text().replace("match: far-*", "match: near-*"))
    with Headless(str(launch), "--machines", str(placement)) as run:
        run.wait_for(r"\[INFO\] \[near-3@r1\]: process started")
        run.wait_for(r"\[near-3@r1\] near up|\[INFO\] \[near-3@r1\]")
        assert run.text.index("[far-1]: process started") < \
            run.text.index("[near-3@r1]: process started")
        code = run.stop()
    assert code == 0, run.text
    wait_for(lambda: remote_sessions(machines, "robot1") == [])


def assert_far_node_fails_alone(launch: Path, placement: Path, says: str) -> None:
    """The node placed on robot1 fails in one line starting with `says`; the node here
    runs all the same; the launch ends with a failure status."""
    with Headless(str(launch), "--machines", str(placement)) as run:
        failed = run.wait_for(r"\[ERROR\] \[far-1@r1\]: failed to start: (.*)\n")
        assert failed.group(1).startswith(says), failed.group(1)
        run.wait_for(r"\[solo-2\] solo up")
        code = run.stop()
    assert code != 0


def test_a_missing_remote_tuilaunch_is_said_for_each_node_placed_there(setup, tmp_path):
    launch, placement = setup
    text = placement.read_text()
    placement.write_text(text.replace(str(tmp_path / "tl"), str(tmp_path / "nowhere" / "tl"),
                                      1))
    assert_far_node_fails_alone(launch, placement, "r1 (robot1): tuilaunch not found there")


RELAUNCH = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
from launch.substitutions import LaunchConfiguration
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('word', default_value='tick'),
        ExecuteProcess(name='far', cmd=['sh', '-c', ['while true; do echo far ',
                       LaunchConfiguration('word'), '; sleep 0.2; done']]),
    ])
"""


def test_a_relaunch_with_new_arguments_is_applied_on_robot1(setup, machines, write):
    from tuilaunch.client.link import Link

    _, placement = setup
    launch = write(RELAUNCH, "relaunch.py")
    name = "relaunched"
    done = run_cli(str(launch), "--machines", str(placement), "--detach", "--name", name)
    assert done.returncode == 0, done.stderr
    try:
        wait_for(lambda: "far tick" in run_cli("logs", name, "far-1").stdout)
        link = Link(name, timeout=None)
        try:
            link.request(Apply(arguments={"word": "tock"}))
        finally:
            link.close()
        wait_for(lambda: "far tock" in run_cli("logs", name, "far-1").stdout)
        share = remote_sessions(machines, "robot1")[0]
        assert share["arguments"] == {"word": "tock"}
    finally:
        stopped = run_cli("stop", name, timeout=120)
    assert stopped.returncode == 0, stopped.stderr
    wait_for(lambda: remote_sessions(machines, "robot1") == [])


def test_a_refused_key_is_said_for_each_node_placed_there(setup, machines, tmp_path):
    launch, placement = setup
    stranger = tmp_path / "stranger_key"
    keygen(stranger)  # a key robot1 does not know
    with open(machines.ssh_config, "a") as config:
        config.write(machines.host_entry("robot1-stranger", machines["robot1"].port,
                                         stranger))
    placement.write_text(placement.read_text().replace("host: robot1,",
                                                       "host: robot1-stranger,"))
    assert_far_node_fails_alone(launch, placement, "r1 (robot1-stranger) refused the login")


def test_a_node_on_robot2_waits_for_a_node_on_robot1(setup, machines, tmp_path):
    launch, placement = setup
    tool = tmp_path / "tl"
    placement.write_text(placement.read_text().replace(
        "placement:\n", f"  r2: {{host: robot2, tuilaunch: {tool}}}\nplacement:\n") +
        "  - {match: near-*, machine: r2}\n")
    with Headless(str(launch), "--machines", str(placement)) as run:
        run.wait_for(r"\[INFO\] \[near-3@r2\]: process started")
        assert run.text.index("[far-1@r1]: process started") < \
            run.text.index("[near-3@r2]: process started")
        assert len(remote_sessions(machines, "robot2")) == 1
        code = run.stop()
    assert code == 0, run.text
    wait_for(lambda: remote_sessions(machines, "robot1") == [])
    wait_for(lambda: remote_sessions(machines, "robot2") == [])


def test_a_mistake_in_the_machines_file_is_one_line_naming_file_and_line(write, tmp_path):
    launch = write(LAUNCH)
    machines_file = tmp_path / "machines.yaml"
    machines_file.write_text("machines:\n  r1: {hots: robot1}\n")
    done = run_cli(str(launch), "--machines", str(machines_file), "--print")
    assert done.returncode == 2
    assert done.stderr.startswith(f"tuilaunch: error: {machines_file}:2:8: machines.r1: "
                                  "unknown field 'hots'\n"), done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""


def test_a_rule_naming_a_node_that_names_itself_says_why_it_places_nothing(tmp_path):
    """`/r1/talker` for a node the launch file does not name (shown `/r1/<talker>`):
    nothing is known of its name before it runs, and the warning offers the process id."""
    launch = tmp_path / "unnamed.launch.py"
    launch.write_text(textwrap.dedent("""\
        from launch import LaunchDescription
        from launch_ros.actions import Node, PushRosNamespace
        from launch.actions import GroupAction


        def generate_launch_description():
            return LaunchDescription([GroupAction([
                PushRosNamespace('r1'),
                Node(package='tuilaunch_demos', executable='talker'),
            ])])
        """))
    machines = tmp_path / "machines.yaml"
    machines.write_text("machines:\n  nuc: {host: nuc.local}\n"
                        "placement:\n  - {match: /r1/talker, machine: nuc}\n")
    printed = run_cli(str(launch), "--machines", str(machines), "--print")
    assert printed.returncode == 0, printed.stderr
    assert "placement rule '/r1/talker' -> nuc places no process: /r1/<talker> names " \
        "itself in its code (the launch file gives no name), so a placement rule cannot " \
        "know it before it runs; match its process id instead: 'talker-*'" in printed.stdout


def boot_late(machines: Machines, alias: str) -> Machine:
    """The sshd of a machine that was off (its ssh config entry names a port where nothing
    listened) starts now, on a port of its own: the entry is pointed at it."""
    late = Machine(alias, machines.folder / alias, machines.authorized)
    machines.machines[alias] = late  # stopped with the others
    config = machines.ssh_config.read_text()
    machines.ssh_config.write_text(re.sub(
        rf"(Host {alias}\n  HostName 127\.0\.0\.1\n  Port )\d+", rf"\g<1>{late.port}", config))
    return late


def test_a_machine_off_at_the_start_is_tried_again_by_a_restart(setup, machines):
    launch, placement = setup
    placement.write_text(placement.read_text().replace("machine: r1", "machine: r3"))
    name = "late"
    done = run_cli(str(launch), "--machines", str(placement), "--detach", "--name", name)
    assert done.returncode == 0, done.stderr
    try:
        def far() -> dict:
            status = json.loads(run_cli("status", name, "--json").stdout)
            return next(p for p in status["processes"] if p["id"] == "far-1")

        wait_for(lambda: far()["state"] == "failed", 90)
        assert "cannot reach r3 (robot3)" in far()["detail"]
        # still off: tried again, and said with this attempt's reason
        refused = run_cli("restart", name, "far-1", timeout=90)
        assert refused.returncode != 0
        # said as it happens, then the result
        assert refused.stderr.startswith("r3: connecting again... (far-1 runs there)\n"), \
            refused.stderr
        assert "far-1 runs on r3, tried again: cannot reach r3 (robot3): " in refused.stderr, \
            refused.stderr
        assert "Traceback" not in refused.stderr
        assert far()["state"] == "failed"
        # the TUI attached: the detail line says why and offers the retry; r tries again
        asyncio.run(tui_tries_the_machine_again(name, json.loads(
            run_cli("status", name, "--json").stdout)))
        # robot3 boots late, as a robot's second computer does: a restart reaches it
        boot_late(machines, "robot3")
        restarted = run_cli("restart", name, "far-1", timeout=150)
        assert restarted.returncode == 0, restarted.stderr
        assert restarted.stdout == "far-1: running\n"
        assert restarted.stderr.startswith("r3: connecting again... (far-1 runs there)\n")
        assert "r3: following session " in restarted.stderr, restarted.stderr
        assert len(remote_sessions(machines, "robot3")) == 1
        wait_for(lambda: "far tick" in run_cli("logs", name, "far-1").stdout)
        launch_log = run_cli("logs", name).stdout
        assert "r3: connecting again... (far-1 runs there)" in launch_log, launch_log
    finally:
        stopped = run_cli("stop", name, timeout=120)
    assert stopped.returncode == 0, stopped.stderr
    wait_for(lambda: remote_sessions(machines, "robot3") == [])


async def tui_tries_the_machine_again(name: str, status: dict) -> None:
    from tuilaunch.tui.output_store import View

    app = placed_app(name, status)
    async with app.run_test(size=(160, 30)) as pilot:
        tree = app.launch_tree
        for _ in range(400):
            if "far-1" in tree.rows and tree.states.get("far-1") == "failed":
                break
            await pilot.pause(0.05)
        detail = ""
        for _ in range(200):
            tree.move_cursor(tree.rows["far-1"])
            await pilot.pause(0.05)
            detail = str(app.detail_bar.render())
            if detail.startswith("far-1"):
                break
        assert "cannot reach r3 (robot3)" in detail and "r: try r3 again" in detail, detail
        await pilot.press("r")
        said: list[str] = []
        for _ in range(600):
            said = [n.message for n in app._notifications]
            if any("tried again" in text for text in said):
                break
            await pilot.pause(0.05)
        assert any(text.startswith("far-1 runs on r3, tried again: cannot reach r3")
                   for text in said), said
        assert "r3: connecting again..." in "\n".join(
            line.text for line in app.store.lines(View(None)))
        # the reply comes at once, the state with the session's next batch of events
        await until(pilot, lambda: tree.states["far-1"] == "failed")
        await pilot.press("d")
        await until(pilot, lambda: app.detached)


SELF_NAMED = """
from launch import LaunchDescription
from launch_ros.actions import Node, PushRosNamespace
from launch.actions import GroupAction


def generate_launch_description():
    return LaunchDescription([GroupAction([
        PushRosNamespace('r2'),
        Node(package='tuilaunch_demos', executable='talker', name='talker'),
        Node(package='tuilaunch_demos', executable='listener'),
    ])])
"""


def test_a_rule_that_places_others_says_which_self_named_node_it_leaves_here(setup, write):
    """`match: /r2/**` places /r2/talker; /r2/<listener> names itself, stays here, and
    that is said once, naming the node and the rule, in --print and at the start."""
    _, placement = setup
    launch = write(SELF_NAMED, "self_named.py")
    placement.write_text(placement.read_text().replace("match: far-*, machine: r1",
                                                       "match: /r2/**, machine: r3"))
    says = ("placement rule '/r2/**' -> r3 leaves listener-2 here: /r2/<listener> names "
            "itself in its code (the launch file gives no name), so a placement rule cannot "
            "know it before it runs; match its process id instead: 'listener-*'")
    printed = run_cli(str(launch), "--machines", str(placement), "--print")
    assert printed.returncode == 0, printed.stderr
    assert printed.stdout.count(says) == 1, printed.stdout
    assert "[talker-1] @r3" in printed.stdout
    with Headless(str(launch), "--machines", str(placement)) as run:
        run.wait_for(r"\[ERROR\] \[talker-1@r3\]: failed to start")  # robot3 is off
        run.stop()
    assert run.text.count(says) == 1, run.text
