"""A launch file is loaded once per launch, by the session's server, as ros2 launch loads it:
`tuilaunch FILE` in a terminal draws the plan the server resolved (the tree is on screen
before the first process starts), `--headless` loads it once too, and a relaunch once more.
A file that does not load is still one line and status 2 in a terminal.

Each launch file's module level appends a line to a file: its lines are the loads."""

from __future__ import annotations

import os
import re
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

from tuilaunch.client.link import open_link
from tuilaunch.client.session_start import spawn_session
from tuilaunch.engine.run.session import session_dir
from tuilaunch.engine.run.session.owner_gate import OWNER_WAIT
from tuilaunch.engine.run.vocabulary.request import Request
from tuilaunch.engine.run.vocabulary.requests import Apply, ShutdownLaunch, Status

from ..conftest import run_cli, run_headless, session_folders, wait_for
from .proc_tree import end, servers_of
from .test_sessions import Terminal as SessionsTerminal

COUNTED = """
import os, sys, time
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess
from launch.conditions import LaunchConfigurationEquals

with open({loads!r}, "a") as loads:  # once per load of this file
    loads.write("load\\n")


def generate_launch_description():
    time.sleep(0.5)  # a big xacro's stand-in
    return LaunchDescription([
        DeclareLaunchArgument("mode", default_value="a", choices=["a", "b"]),
        *[ExecuteProcess(cmd=["sleep", "600"], name=f"leaf_{{i}}") for i in range(1, {n})],
        ExecuteProcess(cmd=["sleep", "600"], name="extra",
                       condition=LaunchConfigurationEquals("mode", "b")),
    ])
"""


def counted_file(folder: Path, leaves: int = 3) -> tuple[Path, Path]:
    """A launch file of `leaves` processes, and the file its loads are counted in."""
    loads = folder / "loads"
    path = folder / "counted.launch.py"
    path.write_text(COUNTED.format(loads=str(loads), n=leaves + 1))
    return path, loads


def plain(screen: bytes) -> bytes:
    """The screen's text, its escape sequences spaces."""
    return re.sub(rb"\x1b\[[0-9;?<>$=]*[a-zA-Z~]", b" ", screen)


def loads_of(loads: Path) -> int:
    return len(loads.read_text().splitlines()) if loads.exists() else 0


class Terminal(SessionsTerminal):
    """`tuilaunch ARGS` on a pseudo-terminal of 120x32, its output read as a terminal's."""

    def __init__(self, *args: str) -> None:
        super().__init__(*args, size=(120, 32))

    def read_until(self, marker: bytes, limit: float = 90.0) -> bytes:
        return super().read_until(marker, limit)

    def row_state(self, process: str, limit: float = 90.0) -> str:
        """The state the first drawing of `process`'s row in the tree says."""
        row = re.compile(rf"{process}\s+\[{process}-\d+\]\s+([a-z]+)".encode())
        end_at = time.monotonic() + limit
        while not (found := row.search(plain(self.screen))):
            assert time.monotonic() < end_at, \
                f"{process}'s row never appeared: {plain(self.screen)[-600:]!r}"
            self.pump(0.1)
        return found.group(1).decode()

    def press(self, key: bytes) -> None:
        os.write(self.master, key)

    def quit(self, limit: float = 90.0) -> int:
        """q, then y in its "Stop them all and quit?", again until the TUI exits."""
        end_at = time.monotonic() + limit
        keys = [b"q", b"y"]
        while self.proc.poll() is None:
            assert time.monotonic() < end_at, "the TUI never exited"
            self.press(keys[0])
            keys.reverse()
            self.pump(0.5)
        return self.wait_exit()

    def wait_exit(self, limit: float = 90.0) -> int:
        code = super().wait_exit(limit)
        for _ in range(20):  # what it printed last (an error line after the TUI's screen)
            self.pump(0.05)
        return code


@pytest.fixture
def folders(tmp_path: Path):
    with session_folders(tmp_path / "log"):
        try:
            yield tmp_path
        finally:
            end(servers_of(tmp_path))


def asked(name: str, request: Request[Any]) -> Any:
    """The session's reply, as another client (a second TUI, a script) asks it; in a thread
    of its own, as a Link runs its own event loop."""

    def ask() -> Any:
        link = open_link(name)
        try:
            return link.request(request)
        finally:
            link.close()

    with ThreadPoolExecutor(max_workers=1) as pool:
        return pool.submit(ask).result()


def launch_log(tmp_path: Path) -> str:
    return "".join(p.read_text() for p in (tmp_path / "log").glob("*/launch.log"))


def test_a_launch_in_a_terminal_loads_its_file_once_and_shows_the_tree_first(folders):
    path, loads = counted_file(folders)
    terminal = Terminal(str(path))
    try:
        # the whole tree, drawn from the server's plan, before any process runs
        assert terminal.row_state("leaf_3") == "waiting"
        assert b"running pid" not in plain(terminal.screen)
        terminal.read_until(b"3 running")
        assert loads_of(loads) == 1
        # the owner showed the plan: the server did not start the launch on its own wait
        assert "did not show the plan" not in launch_log(folders)
        # a relaunch with another value (the Args tab's Apply): read again, once, by the
        # server, and the TUI draws the plan it resolved
        [name] = session_dir.live_sessions()
        asked(name, Apply(arguments={"mode": "b"}))
        terminal.read_until(b"4 running")
        assert loads_of(loads) == 2
        assert terminal.quit() == 0
        wait_for(lambda: not servers_of(folders), what="the session's server ended")
        assert loads_of(loads) == 2
    finally:
        terminal.close()


def test_headless_and_print_load_the_file_once(folders):
    path, loads = counted_file(folders)
    run_headless(path, until=("leaf_3-3",))
    assert loads_of(loads) == 1
    assert run_cli(str(path), "--print").returncode == 0
    assert loads_of(loads) == 2


@pytest.mark.parametrize("broken", ["syntax", "argument"])
def test_a_file_that_does_not_load_is_one_line_and_status_2_in_a_terminal(folders, broken):
    """As today: the line `--print` says, after the TUI's screen is gone; nothing runs."""
    path, _ = counted_file(folders)
    arguments = []
    if broken == "syntax":
        path.write_text(path.read_text() + "\ndef broken(:\n")
    else:
        arguments = ["mode:=c"]  # not one of its choices
    printed = run_cli(str(path), *arguments, "--print")
    assert printed.returncode == 2
    error = printed.stderr.strip()
    assert error.startswith("tuilaunch: error: ")
    terminal = Terminal(str(path), *arguments)
    try:
        assert terminal.wait_exit() == 2
        said = terminal.screen.decode(errors="replace").replace("\r\n", "\n")
        assert said.count("tuilaunch: error:") == 1
        assert error in said
    finally:
        terminal.close()
    assert not servers_of(folders)
    assert "started with pid" not in launch_log(folders)


def test_a_launch_whose_tui_never_shows_the_plan_starts_after_its_wait(folders):
    """A TUI killed (or stuck) before it drew the tree leaves a launch that runs, not one
    that waits forever; one stopped meanwhile starts nothing."""
    path, loads = counted_file(folders)
    for stopped in (False, True):
        starting = spawn_session(str(path), {}, None, folders / "log" / f"s{stopped}",
                                 owner=True)
        server = starting.wait()
        try:
            reply = asked(starting.name, Status())
            assert {p.state for p in reply.processes if p.id.startswith("leaf_")} == {"pending"}
            log = folders / "log" / f"s{stopped}" / "launch.log"
            if stopped:
                asked(starting.name, ShutdownLaunch("stopped before the plan showed"))
                server.wait(timeout=60)
                assert "started" not in log.read_text()
            else:
                wait_for(lambda log=log: log.read_text().count("started leaf_") == 3,
                         timeout=OWNER_WAIT + 60, what="the launch started on its own")
                assert "did not show the plan" in log.read_text()
                asked(starting.name, ShutdownLaunch("test over"))
                server.wait(timeout=60)
        finally:
            if server.poll() is None:
                server.kill()
                server.wait()
    assert loads_of(loads) == 2  # once per launch
