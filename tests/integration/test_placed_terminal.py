"""A node placed on another machine (`--machines`) is typed into as one on this computer is,
and a lost link to that machine is said on its nodes, not hidden behind `running`.

One placed session for the module (the suite stays fast): "robot1" is a real sshd on
127.0.0.1 (tests/integration/sshd.py) running the share of `lines` (a line reader with
emulate_tty=True) and `debugged` (a script on pipes, run under pdb by the tests); `here`
runs on the launching side. The TUI is `tuilaunch attach` in tmux (a real terminal whose
screen is read as drawn; `send-keys` writes a burst in one go, as ssh delivers keys).
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

from ..conftest import run_cli, wait_for
from .proc_tree import cmdline, descendants, terminate
from .session_steps import stop_here
from .sshd import SSHD, Machines, alive
from .terminal_harness import PROGRAMS
from .test_sessions import status, wait_state

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")

NAME = "ptty"
LAUNCH = """
import sys
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='lines', cmd=[sys.executable, {reader!r}], output='screen',
                       emulate_tty=True),
        ExecuteProcess(name='debugged', cmd=[{script!r}], output='screen'),
        ExecuteProcess(name='here', cmd=['sleep', '600']),
    ])
"""
DEBUGGED = """#!{python}
import time
print("debugged runs", flush=True)
while True:
    time.sleep(0.5)
"""


@dataclass
class Placed:
    """The placed session: its machines and the launching side's session folder."""

    machines: Machines
    runtime: Path
    folder: Path

    def status(self, command: bool = False) -> dict:
        """What `status NAME --json` says: the command itself (`command`: its subject), else
        read from this process (the launching side is here), as the tests' other looks."""
        if not command:
            return status(NAME)
        done = run_cli("status", NAME, "--json")
        assert done.returncode == 0, done.stderr
        return json.loads(done.stdout)

    def process(self, process_id: str, command: bool = False) -> dict:
        return next(p for p in self.status(command)["processes"] if p["id"] == process_id)

    def logs(self, process_id: str) -> str:
        return run_cli("logs", NAME, process_id).stdout


@pytest.fixture(name="placed", scope="module")
def placed_fixture(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Placed]:
    folder = tmp_path_factory.mktemp("placedtty")
    with pytest.MonkeyPatch.context() as env:
        machines = Machines(folder / "ssh", aliases=("robot1",))
        # the launching side's own session folder (short: a socket path has 108 bytes)
        runtime = Path(tempfile.mkdtemp(prefix="tlhere"))
        for key, value in {**machines.env(), "XDG_RUNTIME_DIR": str(runtime),
                           "ROS_LOG_DIR": str(folder / "log")}.items():
            env.setenv(key, value)
        script = folder / "debugged.py"
        script.write_text(DEBUGGED.format(python=sys.executable))
        script.chmod(0o755)
        launch = folder / "placed.py"
        launch.write_text(LAUNCH.format(reader=str(PROGRAMS / "line_reader.py"),
                                        script=str(script)))
        placement = folder / "machines.yaml"
        placement.write_text("machines:\n  r1: {host: robot1}\n"
                             "placement:\n  - {match: lines-*, machine: r1}\n"
                             "  - {match: debugged-*, machine: r1}\n")
        placed = Placed(machines, runtime, folder)
        try:
            done = run_cli(str(launch), "--machines", str(placement), "--detach",
                           "--name", NAME)
            assert done.returncode == 0, done.stderr
            for process in ("lines-1", "debugged-2", "here-3"):
                wait_state(NAME, process, "running", timeout=90)
            wait_for(lambda: "ready" in placed.logs("lines-1"), 60, "lines-1 ready")
            yield placed
        finally:
            stop_here(NAME, gone_ok=True)
            servers = [json.loads(info.read_text())["pid"]
                       for info in (runtime / "tuilaunch").glob("*.json")]
            for pid in servers:  # a launching side a failed test left running
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
            machines.stop()
            shutil.rmtree(runtime, ignore_errors=True)


class Tmux:
    """`tuilaunch ARGS` in a tmux pane of its own server: the screen as drawn, keys sent
    in one write."""

    def __init__(self, folder: Path, *args: str, size: tuple[int, int] = (80, 24)) -> None:
        self.socket = f"tl{os.getpid()}-{id(self)}"
        command = " ".join([sys.executable, "-m", "tuilaunch", *args])
        self.tmux("new-session", "-d", "-s", "tl", "-x", str(size[0]), "-y", str(size[1]),
                  # the size is the pane's: a COLUMNS or LINES inherited from the run (CI
                  # sets them) would be Textual's instead
                  f"cd {folder} && env -u COLUMNS -u LINES TERM=xterm-256color {command}; "
                  "sleep 600")

    def tmux(self, *args: str) -> str:
        return subprocess.run(["tmux", "-L", self.socket, "-f", "/dev/null", *args],
                              capture_output=True, text=True, timeout=30,
                              env=os.environ.copy()).stdout

    def screen(self) -> str:
        return self.tmux("capture-pane", "-p", "-t", "tl")

    def wait_for(self, text: str, limit: float = 90.0) -> str:
        shown: list[str] = []

        def check() -> bool:
            shown[:] = [self.screen()]
            return text in shown[0]

        try:
            wait_for(check, limit, text)
        except AssertionError:
            raise AssertionError(f"{text!r} never shown; the screen:\n{shown[0]}") from None
        return shown[0]

    def keys(self, *keys: str) -> None:
        """Keys by tmux's names (Down, C-])."""
        self.tmux("send-keys", "-t", "tl", *keys)

    def burst(self, text: str) -> None:
        """`text` as typed (\r for Enter), in one write: as ssh delivers a burst (tmux's
        key names are not read in it: `ic` is not Insert)."""
        self.tmux("send-keys", "-t", "tl", "-l", text)

    def selected(self) -> str:
        """The selected row, as its detail line (on top) names it: `lines-1 (/lines)`,
        `all nodes` (the words before the state, not the CPU and memory after it)."""
        return (self.screen().splitlines()[3:4] or [""])[0].strip().split(":", 1)[0]

    def select(self, process: str) -> None:
        """Down the tree, one row at a time, until `process` is the selected row. Each Down
        waits for the selected row to change, not the detail line's text: a running row's
        CPU and memory change that every second, and a Down sent on such a change would be
        a second one in flight, landing a row past `process` once it was seen selected."""
        self.wait_for(f"{process}]")
        for _ in range(20):
            row = self.selected()
            if row.startswith(f"{process} ("):
                return
            self.keys("Down")
            wait_for(lambda before=row: self.selected() != before, 30, "the next row")
        raise AssertionError(f"{process} never selected:\n{self.screen()}")

    def close(self) -> None:
        pane = self.tmux("list-panes", "-t", "tl", "-F", "#{pane_pid}").strip()
        where = self.tmux("display-message", "-p", "#{socket_path}").strip()
        self.tmux("kill-server")
        if where:  # its socket file too: nothing of the test is left behind
            Path(where).unlink(missing_ok=True)
        if pane.isdigit():  # the shell and the TUI under it: nothing outlives the test
            for pid in [int(pane), *descendants(int(pane))]:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)


@contextlib.contextmanager
def attached(placed: Placed, *args: str, size: tuple[int, int] = (80, 24)) -> Iterator[Tmux]:
    tui = Tmux(placed.folder, "attach", NAME, *args, size=size)
    try:
        yield tui
    finally:
        tui.close()


def test_status_says_the_terminal_a_node_has_on_its_machine(placed: Placed) -> None:
    said = placed.status(command=True)["processes"]
    lines, debugged, here = (next(p for p in said if p["id"] == process)
                             for process in ("lines-1", "debugged-2", "here-3"))
    assert lines["machine"] == "r1" and lines["terminal"] is True, lines
    assert debugged["terminal"] is False, debugged
    assert here["terminal"] is False


def test_attach_type_types_into_a_node_on_another_machine(placed: Placed) -> None:
    """`attach NAME --type lines` (what `i` does on its row): the keys typed go to the
    node on robot1, `reset` Enter included, which neither restarts nor stops it."""
    before = placed.process("lines-1")["pid"]
    with attached(placed, "--type", "lines") as tui:
        tui.wait_for("typing to lines-1")
        tui.burst("reset\r")
        wait_for(lambda: "got: reset" in placed.logs("lines-1"), 60, "the line typed")
        tui.wait_for("got: reset")
        tui.keys("C-]")  # the keys are tuilaunch's again
        tui.wait_for("Type")
    after = placed.process("lines-1")
    assert after["state"] == "running" and after["pid"] == before, after


def test_i_types_into_the_debugger_of_a_node_under_pdb_on_another_machine(
        placed: Placed) -> None:
    """`g` restarts `debugged` under pdb on robot1 (a terminal there: pdb is typed into);
    `i` then types into pdb: the Enter of its `c` continues the program, it restarts
    nothing (no "Restart it with a terminal?" question answered by it)."""
    with attached(placed, size=(120, 30)) as tui:
        tui.select("debugged-2")
        tui.keys("g")
        tui.wait_for("Restart debugged-2 under")
        tui.burst("python3 -m pdb\r")
        tui.wait_for("(Pdb)")
        under = placed.process("debugged-2")
        assert under["command"][:3] == ["python3", "-m", "pdb"], under
        assert under["terminal"] is True, under
        tui.burst("ic\r")  # i, then the debugger's c and Enter: one burst
        wait_for(lambda: placed.logs("debugged-2").count("debugged runs") == 2, 60,
                 "the program continued under pdb")
        tui.wait_for("typing to debugged-2")
        tui.keys("C-]")
    after = placed.process("debugged-2")
    assert after["state"] == "running" and after["pid"] == under["pid"], after
    assert after["command"][:3] == ["python3", "-m", "pdb"]


def robot1_off(placed: Placed) -> None:
    """robot1 leaves the network: its sshd takes no new login, and every link to it dies
    (the launching side's to its share, an attached TUI's), as a cable pulled out ends
    them once ssh notices."""
    machine = placed.machines["robot1"]
    there = [pid for pid in descendants(machine.proc.pid) if b"__proxy" in cmdline(pid)]
    terminate(machine.proc)
    server = json.loads((placed.runtime / "tuilaunch" / f"{NAME}.json").read_text())["pid"]
    links = [pid for pid in descendants(server) if b"__proxy" in cmdline(pid)]
    assert links, "no ssh link to robot1's share"
    for pid in [*links, *there]:
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)


def robot1_on(placed: Placed) -> None:
    """robot1 is back: its sshd listens again on its port (the share ran on meanwhile)."""
    machine = placed.machines["robot1"]
    with open(machine.log, "ab") as log:
        machine.proc = subprocess.Popen([SSHD, "-D", "-e", "-f", str(machine.config)],
                                        stdin=subprocess.DEVNULL, stdout=log, stderr=log,
                                        start_new_session=True)
    wait_for(machine._listening, 30, "robot1's sshd listening again")


def test_a_node_on_a_machine_whose_link_is_lost_is_not_shown_running(placed: Placed) -> None:
    """Its state is unknown since the link was lost: said on its row, in the header's
    counts and by `status`; once the link is back, it is running again everywhere."""
    pid = placed.process("lines-1")["pid"]
    share = f"{NAME}-r1"
    with attached(placed, size=(120, 30)) as tui, \
            contextlib.closing(Tmux(placed.folder, "attach", f"robot1:{share}")) as there:
        tui.wait_for("3 running")
        tui.select("lines-1")
        there.wait_for(f"[robot1:{share}]")  # robot1's share itself, over ssh, at 80x24
        assert tui.selected() == "lines-1 (/lines)", tui.screen()  # no Down left in flight
        robot1_off(placed)
        try:
            # its lost-link line keeps the latest attempt's reason's end at 80 columns
            said = there.wait_for("Connection refused", 60).splitlines()[0]
            assert said.startswith(f" link to robot1 lost · reconnecting · {share} · R: now ·"
                                   ) and said.rstrip().endswith("… Connection refused"), said
            # the detail line says the selected row whole (the tree cuts it)
            screen = tui.wait_for("lines-1 (/lines): unknown (since the link to r1 was lost)")
            assert "1 running  2 unknown" in screen.splitlines()[0], screen
            assert "? lines [lines-1] @r1 unknown" in screen, screen
            assert "? debugged [debugged-2] @r1 unknown" in screen, screen
            lines = placed.process("lines-1")
            assert lines["state"] == "unknown", lines
            assert lines["detail"] == "since the link to r1 was lost", lines
            table = run_cli("status", NAME).stdout
            assert re.search(r"^  lines-1@r1 +unknown .*since the link to r1 was lost$",
                             table, re.M), table
            assert re.search(r"^  here-3 +running ", table, re.M), table
            # what the pane says: why, and that nothing is known until the link is back
            assert "state unknown until the link to r1 is back: lost the link to robot1" \
                in placed.logs("lines-1")
            assert alive(pid)  # it ran on there all along
        finally:
            robot1_on(placed)
        tui.wait_for("3 running", 120)
        screen = tui.wait_for(f"lines [lines-1] @r1 running pid {pid}")
    back = placed.process("lines-1")
    assert back["state"] == "running" and back["pid"] == pid and back["detail"] is None, back
    assert "the link to r1 is back: running there" in placed.logs("lines-1")
