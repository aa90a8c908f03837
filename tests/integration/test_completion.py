"""Tab completion as a user meets it: a real interactive bash (and zsh) in tmux that ran
`eval "$(tuilaunch completion bash)"`; the test types, presses Tab, and reads the screen.

One session of real rclpy nodes serves the module: its name, its processes, its nodes and
its topics are what a Tab press offers after a session command.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

from ..conftest import session_folders
from .inspector_helpers import NODE_SCRIPT
from .launch_world import make_package
from .session_steps import start_here, stop_here
from .system_packages import program
from .test_sessions import wait_state

pytestmark = pytest.mark.skipif(program("tmux") is None, reason="tmux is not installed and "
                                "could not be (apt-get install tmux)")

DEADLINE = 60.0
DEMO = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('mode', default_value='sim', choices=['sim', 'real', 'replay'],
                              description='where the robot is'),
        DeclareLaunchArgument('rate', default_value='5.0'),
        Node(package='cmp_nodes', executable='inspector_node', name='talker',
             namespace='/cmp', arguments=['talker', '--pub', 'chatter', '--rate', '5']),
    ])
"""
SHARE = {"launch/robot.launch.py": DEMO, "launch/sim_launch.xml": "<launch/>\n",
         "launch/view.launch.yaml": "launch: []\n", "config/params.yaml": "{}\n",
         "launch/helpers.py": "X = 1\n"}


class Shell:
    """An interactive shell in its own tmux server, completion installed as documented."""

    def __init__(self, shell: str, home: Path, cwd: Path) -> None:
        self.socket = f"hands-{uuid.uuid4().hex[:8]}"
        bin_dir = str(Path(sys.executable).parent)
        env = {**os.environ, "PATH": bin_dir + os.pathsep + os.environ.get("PATH", ""),
               "HOME": str(home), "TERM": "xterm"}
        env.pop("TMUX", None)
        if shell == "bash":
            rc = home / ".bashrc"
            rc.write_text(textwrap.dedent("""\
                PS1='$ '
                bind 'set show-all-if-ambiguous on'
                bind 'set completion-query-items 0'
                bind 'set page-completions off'
                eval "$(tuilaunch completion bash)"
                """))
            command = f"bash --noprofile --rcfile {rc} -i"
        else:
            rc = home / ".zshrc"
            rc.write_text(textwrap.dedent("""\
                PS1='$ '
                autoload -U compinit && compinit -u
                eval "$(tuilaunch completion zsh)"
                """))
            env["ZDOTDIR"] = str(home)
            command = "zsh -i"
        subprocess.run(["tmux", "-L", self.socket, "new-session", "-d", "-x", "200", "-y",
                        "50", "-c", str(cwd), command], check=True, env=env)
        self.wait_for(lambda screen: screen.rstrip().endswith("$"), "a prompt")

    def screen(self) -> str:
        return subprocess.run(["tmux", "-L", self.socket, "capture-pane", "-p"],
                              capture_output=True, text=True, check=True).stdout

    def keys(self, *keys: str, literal: bool = False) -> None:
        subprocess.run(["tmux", "-L", self.socket, "send-keys", *(["-l"] if literal else []),
                        *keys], check=True)

    def wait_for(self, check, what: str, limit: float = DEADLINE) -> str:
        end = time.monotonic() + limit
        while True:
            screen = self.screen()
            if check(screen):
                return screen
            if time.monotonic() > end:
                raise AssertionError(f"never saw {what}; the screen:\n{screen}")
            time.sleep(0.1)

    def tab(self, typed: str, expect: list[str], absent: tuple[str, ...] = (),
            tabs: int = 1) -> str:
        """Types `typed` on a fresh line, presses Tab, and returns the screen once every
        word of `expect` is on it (pressing Tab again meanwhile, as a user would)."""
        self.clear()
        self.keys(typed, literal=True)
        self.wait_for(lambda screen: typed.rstrip() in screen, f"{typed!r} typed")
        end = time.monotonic() + DEADLINE
        while True:
            for _ in range(tabs):
                self.keys("Tab")
            try:
                screen = self.wait_for(lambda s: all(w in s for w in expect), str(expect),
                                       limit=5)
                break
            except AssertionError:
                if time.monotonic() > end:
                    raise
        for word in absent:
            assert word not in screen, f"{word!r} offered:\n{screen}"
        assert "Traceback" not in screen
        return screen

    def completes(self, typed: str, result: str) -> None:
        """Types `typed` and Tab: the line becomes `result` (a trailing space included,
        seen by the '#' typed after the Tab)."""
        end = time.monotonic() + DEADLINE
        while True:  # a session's first answer may come late on a busy machine: Tab again
            self.clear()
            self.keys(typed, literal=True)
            self.keys("Tab")
            self.keys("#", literal=True)
            self.wait_for(lambda screen: self.line().endswith("#"), "the line back")
            assert "Traceback" not in self.screen()
            if self.line() == result + "#":
                return
            assert time.monotonic() < end, f"never completed to {result!r}: {self.line()!r}"

    def line(self) -> str:
        """The line being edited: what follows the last prompt. On a busy machine bash may
        redraw it a few columns in, or after what was left of the line before it
        (`tuilaunch wait cmpdemo talker-1 ru$ tuilaunch wait ...`, seen under two CPU
        burners)."""
        lines = [line for line in self.screen().splitlines() if "$ " in line]
        return lines[-1].rsplit("$ ", 1)[1] if lines else ""

    def clear(self) -> None:
        self.keys("C-e", "C-u")  # the line typed so far, erased
        self.keys("clear", "Enter")
        self.wait_for(lambda screen: screen.strip() == "$", "a cleared screen")

    def close(self) -> None:
        subprocess.run(["tmux", "-L", self.socket, "kill-server"], capture_output=True)


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, object]]:
    """A package with launch files in its share, a launch file in the current folder, and a
    running session of that file."""
    root = tmp_path_factory.mktemp("completion")
    prefix = root / "prefix"
    make_package(prefix, "cmp_nodes", ["inspector_node"],
                 probe=f"#!{sys.executable}\n" + NODE_SCRIPT.read_text(), files=SHARE)
    work = root / "work"
    (work / "launch").mkdir(parents=True)
    (work / "demo.launch.py").write_text(textwrap.dedent(DEMO))
    (work / "notes.txt").write_text("not a launch file\n")
    with session_folders(root / "log", prefix):
        # the setting, started and ended from this process: completion is the subject
        start_here(work / "demo.launch.py", "--name", "cmpdemo")
        wait_state("cmpdemo", "talker-1", "running")
        yield {"root": root, "work": work}
        stop_here("cmpdemo")


@pytest.fixture(scope="module")
def bash(world: dict[str, object], tmp_path_factory: pytest.TempPathFactory) -> Iterator[Shell]:
    home = tmp_path_factory.mktemp("home")
    (home / ".ssh").mkdir()  # a host of the ssh config: offered as `nuc:` with the sessions
    (home / ".ssh" / "config").write_text("Host nuc\n  HostName 127.0.0.1\n")
    shell = Shell("bash", home, world["work"])  # type: ignore[arg-type]
    try:
        yield shell
    finally:
        shell.close()


def test_bash_completes_commands_packages_and_launch_files(bash):
    screen = bash.tab("tuilaunch lo", ["logs", "log-level"])
    assert "ls" not in screen.split()
    bash.tab("tuilaunch sta", ["start", "status"])
    bash.completes("tuilaunch stat", "tuilaunch status ")  # one match: completed in the line
    bash.completes("tuilaunch cmp_", "tuilaunch cmp_nodes ")
    screen = bash.tab("tuilaunch cmp_nodes ", ["robot.launch.py", "sim_launch.xml",
                                               "view.launch.yaml"],
                      absent=("params.yaml", "helpers.py", "package.xml"))
    # the current folder: launch files and folders, not every file
    bash.completes("tuilaunch dem", "tuilaunch demo.launch.py ")
    bash.tab("tuilaunch l", ["launch/", "logs", "ls"], absent=("notes.txt",))


def test_bash_completes_launch_arguments_and_their_choices(bash):
    screen = bash.tab("tuilaunch demo.launch.py ", ["mode:=", "rate:="])
    assert "--headless" not in screen  # options only after a '-'
    bash.tab("tuilaunch demo.launch.py mode:=", ["real", "replay", "sim"])
    bash.completes("tuilaunch demo.launch.py mode:=rea",
                   "tuilaunch demo.launch.py mode:=real ")
    bash.tab("tuilaunch cmp_nodes robot.launch.py mo", ["mode:="])
    bash.tab("tuilaunch demo.launch.py --he", ["--headless"])


def test_bash_completes_sessions_processes_topics_and_levels(bash):
    bash.completes("tuilaunch status cmp", "tuilaunch status cmpdemo ")
    bash.tab("tuilaunch logs cmpdemo ", ["talker-1", "/cmp/talker"])
    bash.completes("tuilaunch restart cmpdemo tal", "tuilaunch restart cmpdemo talker-1 ")
    bash.completes("tuilaunch wait cmpdemo talker-1 ru", "tuilaunch wait cmpdemo talker-1 running ")
    bash.completes("tuilaunch params cmpdemo /cmp/t", "tuilaunch params cmpdemo /cmp/talker ")
    bash.tab("tuilaunch log-level cmpdemo /cmp/talker ", ["debug", "info", "warn", "unset"])
    bash.tab("tuilaunch logs cmpdemo --level ", ["DEBUG", "WARN", "ERROR"])
    bash.completes("tuilaunch hz cmpdemo /cmp/ch", "tuilaunch hz cmpdemo /cmp/chatter ")
    bash.tab("tuilaunch completion ", ["bash", "zsh"])
    bash.tab("tuilaunch serve ", ["cmpdemo", "demo.launch.py"])  # a session, or a file


def test_bash_offers_a_sessions_processes_after_it_not_the_hosts(bash):
    bash.tab("tuilaunch stop ", ["cmpdemo", "nuc:"])  # the first word: sessions and hosts
    for command in ("stop", "start", "logs"):
        bash.tab(f"tuilaunch {command} cmpdemo ", ["talker-1", "/cmp/talker"],
                 absent=("nuc:",))
    # a word no process starts may be another session (logs A B, stop A B): a host's too
    for command in ("stop", "logs"):
        bash.completes(f"tuilaunch {command} cmpdemo nu", f"tuilaunch {command} cmpdemo nuc:")
    # stop and start take several processes
    bash.completes("tuilaunch stop cmpdemo /cmp/talker tal",
                   "tuilaunch stop cmpdemo /cmp/talker talker-1 ")
    bash.completes("tuilaunch start cmpdemo talker-1 /cmp/t",
                   "tuilaunch start cmpdemo talker-1 /cmp/talker ")


def test_bad_input_completes_to_nothing_and_never_hangs_the_shell(bash):
    for typed in ("tuilaunch logs nosuch ", "tuilaunch status no/such/dir:",
                  "tuilaunch nosuchfile.py ", "tuilaunch cmp_nodes nosuch.launch.py m"):
        bash.clear()
        bash.keys(typed, literal=True)
        bash.keys("Tab")
        bash.keys("X", literal=True)  # typed after the Tab: the shell took the key back
        screen = bash.wait_for(lambda s, typed=typed: (typed + "X") in s, "the line back")
        assert "Traceback" not in screen and "error" not in screen


def test_an_unreachable_host_gives_up_within_the_deadline(world, tmp_path_factory):
    """`HOST:<Tab>` for a host whose ssh never answers: the shell takes keys again after
    the completion's deadline, with nothing printed."""
    home = tmp_path_factory.mktemp("home-ssh")
    stuck = home / "stuck-ssh"
    stuck.write_text("#!/bin/sh\nexec sleep 60\n")
    stuck.chmod(0o755)
    os.environ["TUILAUNCH_SSH_COMMAND"] = str(stuck)
    try:
        shell = Shell("bash", home, world["work"])  # type: ignore[arg-type]
    finally:
        del os.environ["TUILAUNCH_SSH_COMMAND"]
    try:
        shell.keys("tuilaunch status farhost:", literal=True)
        shell.keys("Tab")
        shell.keys("X", literal=True)
        screen = shell.wait_for(lambda s: "farhost:X" in s, "the line back")
        assert "Traceback" not in screen
    finally:
        shell.close()


def test_the_completion_path_imports_neither_rclpy_nor_textual(world):
    line = "tuilaunch lo"
    done = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "tuilaunch"], capture_output=True,
        text=True, timeout=60, pass_fds=(),
        env={**os.environ, "_ARGCOMPLETE": "1", "COMP_LINE": line,
             "COMP_POINT": str(len(line)), "_ARGCOMPLETE_STDOUT_FILENAME": os.devnull})
    imported = {row.split("|")[-1].strip().split(".")[0]
                for row in done.stderr.splitlines() if row.startswith("import time:")}
    assert "argcomplete" in imported
    assert not imported & {"rclpy", "textual", "yaml", "rich"}, sorted(imported)


def test_zsh_completes_commands_and_sessions(world, tmp_path_factory):
    if program("zsh") is None:  # installed as root, as openssh-server and gdb are
        pytest.skip("zsh is not installed and could not be (apt-get install zsh)")
    shell = Shell("zsh", tmp_path_factory.mktemp("zhome"), world["work"])  # type: ignore[arg-type]
    try:
        shell.tab("tuilaunch lo", ["logs", "log-level"])
        shell.completes("tuilaunch status cmp", "tuilaunch status cmpdemo ")
        shell.tab("tuilaunch demo.launch.py mode:=", ["real", "replay", "sim"])
    finally:
        shell.close()
