"""What a third hour of demanding use found, on a real terminal: a `y` typed with `i` never
answers the question `i` opens; `t` on a group starts what the plan runs, never a node its
condition skipped, and the session refuses that node's start for any client.

One session (a detached session server) for the module; each test attaches a TUI to it in
a real terminal (tmux), and writes its keys as one burst, as ssh delivers a typed line.
The App's own side (`i` on a row that is no node, questions that open on their safe
answer, a read-only view's keys) is tested over an in-memory session in
tests/unit/test_app_later_hours.py.
"""

from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from tuilaunch.client.link import open_link
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.engine.run.vocabulary.requests import Start
from tuilaunch.tui.key_order import BURST_GAP

from .proc_tree import end, servers_of
from .session_steps import start_here, stop_here
from .test_sessions import status, wait_state

pytestmark = pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")

DEADLINE = 30.0

THREE = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, GroupAction
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('listener', default_value='true'),
        GroupAction([
            ExecuteProcess(name='talker', cmd=['sleep', '600']),
            GroupAction([ExecuteProcess(name='listener', cmd=['sleep', '600'])],
                        condition=IfCondition(LaunchConfiguration('listener'))),
            ExecuteProcess(name='piped', cmd=['sleep', '600']),
        ]),
    ])
"""


@pytest.fixture(scope="module")
def session() -> Iterator[str]:
    """One session of THREE with `listener:=false` (listener-2 skipped) for the module, in
    a private session folder; stopped, with whatever it runs, at the end."""
    folder = Path(tempfile.mkdtemp(prefix="tl3"))
    logs = folder / "log"
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("XDG_RUNTIME_DIR", str(folder))
        patch.setenv("ROS_LOG_DIR", str(logs))
        path = folder / "three.launch.py"
        path.write_text(THREE)
        name = start_here(path, "listener:=false", "--name", "three")
        try:
            wait_state(name, "piped-3", "running")
            yield name
        finally:
            stop_here(name, gone_ok=True)
            end([json.loads(info.read_text())["pid"]
                 for info in (folder / "tuilaunch").glob("*.json")])
            end(servers_of(logs))
            shutil.rmtree(folder, ignore_errors=True)


def states(name: str) -> dict[str, str]:
    return {p["id"]: p["state"] for p in status(name)["processes"]}


def pids(name: str) -> dict[str, int | None]:
    return {p["id"]: p["pid"] for p in status(name)["processes"]}


def wait_for(check: Callable[[], object], what: str, seen: Callable[[], object]) -> None:
    end_at = time.monotonic() + DEADLINE
    while not check():
        if time.monotonic() > end_at:
            raise AssertionError(f"not seen within {DEADLINE} s: {what}; saw:\n{seen()}")
        time.sleep(0.1)


class Tmux:
    """`tuilaunch attach` in a tmux pane of its own server (a private socket): its screen
    as tmux draws it, keys written by `send-keys -l` as one burst."""

    def __init__(self, *args: str) -> None:
        self.socket = f"tl3-{uuid.uuid4().hex[:8]}"
        env = " ".join(f"{k}={shlex.quote(os.environ[k])}"
                       for k in ("XDG_RUNTIME_DIR", "ROS_LOG_DIR", "PATH"))
        command = " ".join(shlex.quote(a) for a in (sys.executable, "-m", "tuilaunch", *args))
        self.tmux("new-session", "-d", "-x", "140", "-y", "30",
                  f"env -u COLUMNS -u LINES {env} TERM=xterm-256color {command}; "
                  "echo TUI-ENDED $?; sleep 600")  # the size is the pane's, not pytest's

    def tmux(self, *args: str) -> str:
        return subprocess.run(["tmux", "-L", self.socket, *args], capture_output=True,
                              text=True, check=True).stdout

    def screen(self) -> str:
        return self.tmux("capture-pane", "-p")

    def shows(self, text: str) -> None:
        wait_for(lambda: text in self.screen(), f"{text!r} on screen", self.screen)

    def toasts(self) -> str:
        """The toasts' text, their lines joined (a toast wraps at its own width)."""
        parts = [line.split("▌", 1)[1].strip() for line in self.screen().splitlines()
                 if "▌" in line]
        return " ".join(part for part in parts if part)

    def says(self, text: str) -> None:
        wait_for(lambda: text in self.toasts(), f"{text!r} said", self.screen)

    def burst(self, keys: str) -> None:
        """`keys` in one write, as ssh delivers a typed line (`\\r`: Enter)."""
        self.tmux("send-keys", "-l", keys)

    def keys(self, *names: str) -> None:
        """Named keys (Down, Home), each its own write."""
        self.tmux("send-keys", *names)

    def close(self) -> None:
        subprocess.run(["tmux", "-L", self.socket, "kill-server"], capture_output=True)


@pytest.fixture
def attached(session: str) -> Iterator[Callable[..., Tmux]]:
    """Attaches a TUI to the module's session (more arguments: `--read-only`); every pane
    is closed after the test (an attached client leaves the session running)."""
    panes: list[Tmux] = []

    def attach(*args: str) -> Tmux:
        pane = Tmux("attach", session, *args)
        panes.append(pane)
        pane.shows("2 of 2 processes running")  # the tree drawn, the root selected
        return pane

    yield attach
    for pane in panes:
        pane.close()


def row(pane: Tmux, down: int, detail: str) -> None:
    """The tree's cursor `down` rows below the root (the group 2, piped-3 6), once the line
    above the tree says `detail` of it (`group:`, `piped-3 (`)."""
    pane.keys("Home", *["Down"] * down)
    pane.shows(detail)


def test_a_question_i_opens_waits_for_a_key_typed_once_it_shows(session, attached):
    """`iyes` Enter on a node started with pipes restarted it with a terminal: the `y`
    answered the question `i` opened. Now the question stays, says why the keys went
    nowhere, and only a key typed after it answers it."""
    before = pids(session)
    pane = attached()
    row(pane, 6, "piped-3 (/piped): running")
    pane.burst("iyes\r")
    pane.shows("Restart it with a terminal")
    pane.says("The keys typed with i were not sent")
    # a person's pause before the next key: a key within key_order.BURST_GAP (0.3 s) of the
    # dropped burst would be dropped with it; meanwhile a `y` of the burst would have
    # answered
    time.sleep(3 * BURST_GAP)
    assert "Restart it with a terminal" in pane.screen()  # not answered by the burst
    assert pids(session) == before
    pane.burst("n")  # typed once the question shows: it answers
    wait_for(lambda: "Restart it with a terminal" not in pane.screen(), "the question gone",
             pane.screen)
    assert pids(session) == before


def test_t_on_a_group_never_starts_the_node_its_condition_skipped(session, attached):
    """`listener:=false`: stop the group, start it again: talker-1 and piped-3 run, and
    listener-2 stays skipped. The session refuses its start for any client, with one
    line."""
    pane = attached()
    row(pane, 2, "group: 2 of 3 processes running")
    pane.burst("s")
    pane.shows("Stop all 2 running processes")
    pane.burst("y")
    wait_for(lambda: states(session) == {"talker-1": "exited", "listener-2": "skipped",
                                         "piped-3": "exited"}, "the group stopped",
             lambda: states(session))
    # `t` is greyed while this client still shows a process running (a user sees the row
    # first): pressed once its own detail line says the stop is over
    wait_for(lambda: re.search(r"group: 0 of 3 processes running(?!,)", pane.screen()),
             "the stopped group on screen", pane.screen)
    pane.burst("t")
    wait_for(lambda: states(session) == {"talker-1": "running", "listener-2": "skipped",
                                         "piped-3": "running"}, "the group started again",
             lambda: states(session))
    link = open_link(session)
    try:
        with pytest.raises(SessionError, match=r"listener-2 is skipped by its condition "
                           r"\(if \$\(var listener\) = 'false'\): the launch does not run it"):
            link.request(Start(process="listener-2"))
    finally:
        link.close()
    assert states(session)["listener-2"] == "skipped"


