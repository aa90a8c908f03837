"""Relaunching as an operator does it: names that follow the nodes a relaunch moves, a
launch file edited on disk, a mistyped argument, and what another client of the session sees.

Real session servers running the demo's rclpy nodes (or shell processes), the TUI attached
through Textual's pilot, and the command line run as a user types it."""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path

from textual.pilot import Pilot
from textual.widgets import Input, Static

from tuilaunch.engine.run.vocabulary.requests import Apply
from tuilaunch.tui.app import TuiLaunchApp, make_app
from tuilaunch.tui.screens.dialogs import ChoiceScreen
from tuilaunch.tui.screens.topics_panel import TopicsPanel

from ..conftest import run_cli, wait_for
from .session_steps import start_here, stop_here
from .test_sessions import runtime, status, tl, wait_state  # noqa: F401
from .test_tui import BRINGUP, until


@asynccontextmanager
async def session_tui(path: str, *args: str, wait: tuple[str, ...] = (),
                      size: tuple[int, int] = (120, 36), owner: bool = True)\
        -> AsyncIterator[tuple[TuiLaunchApp, Pilot, str]]:
    """The launch in a session server and the TUI on it: as `tuilaunch FILE` runs it
    (`owner`), or as `tuilaunch attach` opens it."""
    name = start_here(path, *args)
    try:
        for process in wait:
            wait_state(name, process, "running")
        info = status(name)
        app = make_app(path, info["arguments"], Path(info["log_dir"]), session_name=name,
                       owner=owner)
        async with app.run_test(size=size) as pilot:
            yield app, pilot, name
    finally:
        stop_here(name, gone_ok=True)


def detail(app: TuiLaunchApp) -> str:
    return str(app.query_one("#detail", Static).render())


def header(app: TuiLaunchApp) -> str:
    return str(app.query_one("#status", Static).render())


def preview_text(app: TuiLaunchApp) -> str:
    return str(app.query_one("#args-preview", Static).render())


async def test_names_follow_a_relaunch_that_moves_the_nodes(runtime):  # noqa: F811
    async with session_tui(BRINGUP, "robot:=rl1", "listener:=false", "services:=false",
                           wait=("talker-1",)) as (app, pilot, name):
        tree = app.launch_tree
        await until(pilot, lambda: "talker-1" in tree.rows)
        tree.move_cursor(tree.rows["talker-1"])
        await until(pilot, lambda: "talker-1 (/rl1/talker)" in detail(app))
        old_pid = status(name)["processes"][0]["pid"]

        # the Args tab: robot rl1 -> rl2, F5
        await pilot.press("2")
        field = app.query_one("#arg-robot", Input)
        field.focus()
        await pilot.press("ctrl+u", *"rl2", "f5")
        await until(pilot, lambda: app.session.arguments.get("robot") == "rl2")
        await until(pilot, lambda: next(p for p in status(name)["processes"]
                                        if p["id"] == "talker-1")["pid"] not in (None, old_pid),
                    every=lambda: None)
        await pilot.press("escape", "1")
        tree.focus()
        await until(pilot, lambda: "talker-1" in tree.rows)
        tree.move_cursor(tree.rows["talker-1"])
        # the header line and the tree follow the node to its new namespace
        await until(pilot, lambda: "talker-1 (/rl2/talker)" in detail(app))
        assert "robot:=rl2" in header(app)
        assert "/rl1/" not in detail(app)

        # o: the Topics tab lists the moved node's topics
        await pilot.press("o")  # the Topics tab's panel is made as it first shows
        await until(pilot, lambda: app.tabs.active == "topics")
        panel = app.query_one(TopicsPanel)
        # the node o asked for, listed once the panel is there (a loaded machine: later)
        await until(pilot, lambda: panel.node == "/rl2/talker")
        await until(pilot, lambda: "/rl2/chatter" in panel.shown)
        assert not any(topic.startswith("/rl1/") for topic in panel.shown)

        # L: the log level question names the node where it is now
        await pilot.press("1")
        tree.focus()
        tree.move_cursor(tree.rows["talker-1"])
        await pilot.press("L")
        await until(pilot, lambda: isinstance(app.screen, ChoiceScreen))
        question = app.screen
        assert isinstance(question, ChoiceScreen)
        assert question.question.startswith("Log level of /rl2/talker (talker-1)")
        await pilot.press("escape")

        # the topics listed by `o` follow the node when the next relaunch moves it again
        await pilot.press("2")
        app.query_one("#arg-robot", Input).focus()
        await pilot.press("ctrl+u", *"rl5", "f5")
        await until(pilot, lambda: panel.node == "/rl5/talker")
        await pilot.press("escape", "5")
        await until(pilot, lambda: "/rl5/chatter" in panel.shown)
        assert not any(topic.startswith("/rl2/") for topic in panel.shown)

        # the command line, after a relaunch, finds the node by its process id too: the
        # talker reported its name in its first line, the server learnt /rl5/talker
        await until(pilot, lambda: "/rl5/chatter" in tl("topics", name, "--node",
                                                        "talker-1", check=False).stdout,
                    every=lambda: None)
        await pilot.press("2")
        app.query_one("#arg-robot", Input).focus()
        await pilot.press("ctrl+u", *"rl4", "f5")
        await until(pilot, lambda: status(name)["arguments"].get("robot") == "rl4")
        wait_state(name, "talker-1", "running")
        # at once: the server waits a moment for the restarted talker to say its name
        topics = tl("topics", name, "--node", "talker-1", check=False)
        assert topics.returncode == 0, topics.stderr
        assert "/rl4/chatter" in topics.stdout and "/rl5/" not in topics.stdout
        dumped = tl("params", name, "talker-1", "--dump")
        assert dumped.stdout.startswith("/rl4/talker:")
        level = tl("log-level", name, "talker-1", "debug", check=False)
        assert "/rl5/talker" not in level.stdout + level.stderr


EDITABLE = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('word', 'alpha')
    sl.add_action(ExecuteProcess(name='echo', cmd=[
        'sh', '-c', 'echo {said} "$0"; exec sleep 600', sl.arg('word')]))
    {extra}
    return sl.launch_description()
"""
EXTRA = ("sl.declare_arg('loud', 'no'); "
         "sl.add_action(ExecuteProcess(name='extra', cmd=['sh', '-c', 'exec sleep 600']))")


def pid_of(name: str, process: str) -> int | None:
    return next(p["pid"] for p in status(name)["processes"] if p["id"] == process)


async def test_a_relaunch_runs_the_edited_file_and_refuses_one_that_no_longer_loads(
        runtime, write):  # noqa: F811
    path = write(EDITABLE.format(said="word", extra=""))
    async with session_tui(str(path), wait=("echo-1",)) as (app, pilot, name):
        first = pid_of(name, "echo-1")
        # the operator edits the file: the echo says another thing, a process is added
        path.write_text(EDITABLE.format(said="said", extra=EXTRA))
        await pilot.press("2")
        await until(pilot, lambda: "changed on disk" in preview_text(app))
        # the form shows what runs until F5: the edit's new argument is said
        assert "test_launch.py changed on disk: declares loud; adds: extra-2; changes: echo-1" \
            in preview_text(app)
        # and changes an argument too, then F5: the edited file runs, with the new value
        app.query_one("#arg-word", Input).focus()
        await pilot.press("ctrl+u", *"beta", "f5")
        await until(pilot, lambda: status(name)["arguments"] == {"word": "beta"})
        wait_state(name, "extra-2", "running")
        wait_state(name, "echo-1", "running")
        assert pid_of(name, "echo-1") != first
        await until(pilot, lambda: "said beta" in tl("logs", name, "echo-1").stdout,
                    every=lambda: None)
        await until(pilot, lambda: "extra-2" in app.launch_tree.rows)
        # the argument the edited file declares joins the form
        await until(pilot, lambda: bool(app.query("#arg-loud")))

        # a file that no longer loads: F5 is refused with file:line, nothing stops
        running = {p: pid_of(name, p) for p in ("echo-1", "extra-2")}
        path.write_text(EDITABLE.format(said="said", extra=EXTRA).replace(
            "return sl.launch_description()", "return sl.launch_description("))
        await pilot.press("escape", "f5")
        await until(pilot, lambda: "no longer loads" in preview_text(app))
        text = preview_text(app)
        assert f"{path}:10: syntax error" in text
        assert "the launch runs on as it was" in text
        assert app.query_one("#args-preview").has_class("error")
        assert {p: pid_of(name, p) for p in running} == running
        assert status(name)["arguments"] == {"word": "beta"}

        # another client (or a TUI whose preview came before the edit) asks the server to
        # apply: the server reads the file again and refuses, with the file's line
        path.write_text(EDITABLE.format(said="said", extra="raise RuntimeError('oops')"))
        message = refused_elsewhere(name, word="gamma")
        assert "cannot apply: the launch file no longer loads" in message
        assert f"{path}:9" in message and "RuntimeError: oops" in message
        assert {p: pid_of(name, p) for p in running} == running
        assert status(name)["arguments"] == {"word": "beta"}


def refused_elsewhere(name: str, **arguments: str) -> str:
    """What the session says to another client asking it to apply `arguments`, which it
    must refuse."""
    from tuilaunch.client.link import open_link
    from tuilaunch.engine.run.session.session_dir import SessionError

    link = open_link(name)
    try:
        link.request(Apply(arguments=arguments))
    except SessionError as exc:
        return str(exc)
    finally:
        link.close()
    raise AssertionError("the relaunch was applied")


TYPO = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('robot', 'r1')
    with sl.group(ns=sl.arg('robot')):
        sl.add_action(ExecuteProcess(name='say', cmd=['sh', '-c', 'echo in "$0"; exec sleep 600',
                                                      sl.arg('robot')]))
    return sl.launch_description()
"""


def test_a_mistyped_argument_keeps_its_warning_line_headless_and_in_print(write):
    path = write(TYPO.replace("exec sleep 600", "true"))
    printed = run_cli(str(path), "robto:=r2", "--print")
    assert printed.returncode == 0
    assert "argument 'robto' is not declared by test_launch.py or its includes; did you mean " \
        "'robot'?" in printed.stdout + printed.stderr
    ran = run_cli(str(path), "robto:=r2", "--headless")
    assert ran.returncode == 0, ran.stderr
    assert "tuilaunch: warning: argument 'robto' is not declared by test_launch.py or its " \
        "includes; did you mean 'robot'? (declared: robot)" in ran.stderr
    assert "[say-1] in r1" in ran.stdout  # run with the declared argument's default


SHELL = EDITABLE.format(said="word", extra=(
    "sl.add_action(ExecuteProcess(name='bad', cmd=['sh', '-c', 'sleep 1; exit 3']))"))


def apply_elsewhere(name: str, **arguments: str) -> None:
    """Another operator's client relaunches the session."""
    from tuilaunch.client.link import open_link

    link = open_link(name)
    try:
        link.request(Apply(arguments=arguments))
    finally:
        link.close()


async def test_an_attached_client_says_when_the_session_is_stopped_elsewhere(
        runtime, write, monkeypatch):  # noqa: F811
    # it stays on screen a moment before it leaves: 1 s here, not the 3 s a reader gets
    monkeypatch.setattr("tuilaunch.tui.session_link.ENDED_ELSEWHERE_PAUSE", 1.0)
    path = write(SHELL)
    # a relaunch made by another client before this one attached
    name = start_here(str(path))
    wait_state(name, "echo-1", "running")
    apply_elsewhere(name, word="beta")
    wait_state(name, "echo-1", "running")
    info = status(name)
    app = make_app(str(path), info["arguments"], Path(info["log_dir"]), session_name=name)
    try:
        async with app.run_test(size=(100, 30)) as pilot:
            await until(pilot, lambda: "echo-1" in app.launch_tree.rows)
            await until(pilot, lambda: app.query_one("#arg-word", Input).value == "beta")
            # what happened before attaching is in the panes, not news in a toast
            said = [n.message for n in app._notifications]
            assert not any("relaunched by another client" in m for m in said), said
            # a relaunch while attached is news
            apply_elsewhere(name, word="gamma")
            await until(pilot, lambda: any("relaunched by another client: word:=gamma"
                                           in n.message for n in app._notifications))
            # a relaunch for an edited file says so, not only the values (or "defaults")
            path.write_text(SHELL.replace("echo word", "echo words"))
            apply_elsewhere(name, word="gamma")
            said_edit = f"relaunched by another client: {path.name} changed; word:=gamma"
            await until(pilot, lambda: any(said_edit == n.message
                                           for n in app._notifications))
            # `tuilaunch stop` elsewhere: said here before the TUI leaves
            stopping = run_cli("stop", name)
            assert stopping.returncode == 0, stopping.stderr
            await until(pilot, lambda: "stopped elsewhere" in header(app))
            assert f"session {name} was stopped elsewhere (tuilaunch stop); leaving" \
                == header(app)
            assert any("stopped elsewhere" in n.message for n in app._notifications)
            assert app.is_running  # still on screen, long enough to be read
            await until(pilot, lambda: not app.is_running)
    finally:
        stop_here(name, gone_ok=True)
    assert app.ended_elsewhere == "tuilaunch stop"



def quit_after_a_failure(owner) -> str:
    """`q` `y` on a TUI whose run failed: it exits 1 and leaves what failed in the shell;
    returns the terminal's text."""
    os.write(owner.master, b"q")
    owner.read_until(b"Stop")
    os.write(owner.master, b"y")
    assert owner.wait_exit() == 1
    owner.read_until(b"every log of this launch")
    return owner.screen.decode(errors="replace")


def test_the_shell_says_what_ended_the_tui(runtime, write):  # noqa: F811
    """`tuilaunch attach` on a terminal: stopped elsewhere, it leaves a line in the shell;
    `tuilaunch FILE` quit after a process failed leaves what failed and where its log is."""
    from .test_sessions import Terminal

    path = write(SHELL)
    name = start_here(str(path))
    wait_state(name, "echo-1", "running")
    wait_state(name, "bad-2", "failed")  # before the stop, not raced by it
    attached = Terminal("attach", name)
    try:
        attached.read_until(b"echo-1")
        assert run_cli("stop", name).returncode == 0
        assert attached.wait_exit() == 1  # bad-2 failed in this launch
        attached.read_until(f"session {name} was stopped elsewhere (tuilaunch stop)".encode())
        attached.read_until(b"tuilaunch: bad-2 failed (exit code 3)")
    finally:
        attached.close()

    owner = Terminal(str(path))
    try:
        owner.read_until(b"bad-2")  # the tree, drawn from the plan the session's server sent

        def sessions() -> list[str]:
            return [line.split()[0] for line in tl("ls").stdout.splitlines()[1:] if line]

        wait_for(sessions, what="the TUI's session in tuilaunch ls")
        names = sessions()
        wait_state(names[-1], "bad-2", "failed")
        log_dir = status(names[-1])["log_dir"]
        text = quit_after_a_failure(owner)
        assert f"tuilaunch: bad-2 failed (exit code 3); its output: {log_dir}/bad-2.log" in text
        assert f"tuilaunch: every log of this launch: {log_dir}" in text
        assert "echo-1 failed" not in text  # stopped by the quit: not a failure
    finally:
        owner.close()


RESPAWNED = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='crashy', respawn=True, respawn_delay=0.2,
        cmd=['sh', '-c', 'if [ -e {mark} ]; then echo again; exec sleep 600; fi; '
                         'touch {mark}; exit 3'], output='screen')])
"""


def test_the_shell_says_which_crash_made_the_exit_status_1(runtime, write, tmp_path):  # noqa: F811
    """A node that crashed once and was respawned runs fine at the quit, yet the run's
    exit status is 1 (it crashed): the shell says which process and where its log is, not
    a bare non-zero status."""
    from .test_sessions import Terminal

    path = write(RESPAWNED.format(mark=tmp_path / "crashed-once"))
    owner = Terminal(str(path))
    try:
        owner.read_until(b"again")  # died once, runs again
        text = quit_after_a_failure(owner)
        assert "tuilaunch: crashy-1 died during the run (exit code 3), then ran again; " \
               "its output: " in text
    finally:
        owner.close()


MAIN = """
import os
from launch import LaunchDescription
from launch.actions import IncludeLaunchDescription
from launch.launch_description_sources import PythonLaunchDescriptionSource
def generate_launch_description():
    here = os.path.dirname(__file__)
    return LaunchDescription([IncludeLaunchDescription(
        PythonLaunchDescriptionSource(os.path.join(here, 'part_launch.py')))])
"""
PART = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='part', cmd=[
        'sh', '-c', 'echo {said}; exec sleep 600'])])
"""


async def test_an_edited_included_file_is_previewed_and_applied_by_f5(
        runtime, write):  # noqa: F811
    part = write(PART.format(said="first"), "part_launch.py")
    path = write(MAIN, "main_launch.py")
    async with session_tui(str(path), wait=("part-1",)) as (app, pilot, name):
        first = pid_of(name, "part-1")
        part.write_text(PART.format(said="second"))
        await pilot.press("2")
        await until(pilot, lambda: "changed on disk" in preview_text(app))
        assert preview_text(app).startswith(
            "a file main_launch.py includes changed on disk: changes: part-1.")
        await pilot.press("f5")
        await until(pilot, lambda: "Applied." in preview_text(app))
        wait_state(name, "part-1", "running")
        assert pid_of(name, "part-1") != first
        await until(pilot, lambda: "second" in tl("logs", name, "part-1").stdout,
                    every=lambda: None)


def test_the_session_reads_an_edited_file_and_keeps_the_running_one_when_it_breaks(write):
    """The engine's rules under the form: a preview reads the file when it changed on disk
    and says what the edit alone alters; a file that no longer loads leaves the session
    (plan, values, file) as it was; F5 (`reread`) reads it whatever its stamp says."""
    from tuilaunch.engine.plan.session import Session

    path = write(EDITABLE.format(said="word", extra=""))
    session = Session(str(path), {})
    assert session.preview({}).file_changes is None  # nothing changed on disk
    path.write_text(EDITABLE.format(said="said", extra=EXTRA))
    preview = session.preview({"word": "beta"})
    assert preview.edited == "test_launch.py"
    assert preview.file_changes is not None
    assert (preview.file_changes.start, preview.file_changes.stop) == (
        ["echo-1", "extra-2"], ["echo-1"])
    assert preview.diff is not None and "extra-2" in preview.diff.start
    before = session.plan
    path.write_text("def generate_launch_description(:\n")
    broken = session.preview({"word": "gamma"}, reread=True)
    assert broken.plan is None and broken.error is not None
    assert broken.error.startswith(f"the launch file no longer loads: {path}:1: syntax error")
    assert session.plan is before and session.arguments == {}
    path.write_text(EDITABLE.format(said="said", extra=EXTRA))
    session.accept(session.preview({"word": "beta"}, reread=True))
    assert [p.id for p in session.plan.processes] == ["echo-1", "extra-2"]
    assert session.preview({}).file_changes is None  # what runs is the file on disk


async def test_attaching_after_the_file_was_edited_shows_what_runs_and_what_f5_would_change(
        runtime, write):  # noqa: F811
    """The file was edited while the session ran: `tuilaunch attach` draws the plan that
    runs (the server's), and its Args tab says what the edit would change."""
    from tuilaunch.cli.commands import edited_since
    from tuilaunch.client.served_session import ServedSession

    path = write(EDITABLE.format(said="word", extra=""))
    name = start_here(str(path))
    try:
        wait_state(name, "echo-1", "running")
        info = status(name)
        assert not edited_since(info["file"], info["file_stamp"])
        path.write_text(EDITABLE.format(said="said", extra=EXTRA))
        assert edited_since(info["file"], info["file_stamp"])
        app = make_app(str(path), info["arguments"], Path(info["log_dir"]), session_name=name,
                       served=edited_since(info["file"], info["file_stamp"]))
        async with app.run_test(size=(120, 36)) as pilot:
            assert isinstance(app.session, ServedSession)
            await until(pilot, lambda: "echo-1" in app.launch_tree.rows)
            assert "extra-2" not in app.launch_tree.rows  # not running: not in the tree
            await pilot.press("2")
            await until(pilot, lambda: "changed on disk" in preview_text(app))
            assert "test_launch.py changed on disk: declares loud; adds: extra-2; " \
                "changes: echo-1" in preview_text(app)
            await pilot.press("f5")
            await until(pilot, lambda: "extra-2" in app.launch_tree.rows)
            wait_state(name, "extra-2", "running")
            app.leaving.detach()
            await until(pilot, lambda: app.detached)
    finally:
        stop_here(name, gone_ok=True)


# `slow`, in its first run (word alpha), saves its state on SIGINT until the test releases it
# (RELEASE, a file): the relaunch that stops it waits meanwhile, echo-1 stopped; the run the
# relaunch starts (beta) stops at once
SLOW_STOP = EDITABLE.format(said="quick", extra=(
    "sl.add_action(ExecuteProcess(name='slow', sigterm_timeout='120', cmd=['sh', '-c', "
    "'if [ \"$0\" = alpha ]; then trap \"while [ ! -e RELEASE ]; do sleep 0.05; done; "
    "exit 0\" INT; fi; echo slow \"$0\"; while true; do sleep 0.1; done', sl.arg('word')]))"))


def test_wait_running_waits_through_a_relaunch_that_stopped_the_process(
        runtime, write, tmp_path):  # noqa: F811
    """A script relaunches, then waits for a node to run again: the node the relaunch
    stopped to start it with the new values is not an end (seen in CI as `talker-1
    exited, not running`, when the wait came between the stop and the start)."""
    from .test_logs_command import _has_socket

    release = tmp_path / "release"
    name = start_here(str(write(SLOW_STOP.replace("RELEASE", str(release)))))
    try:
        for process in ("echo-1", "slow-2"):
            wait_state(name, process, "running")
        old_pid = next(p["pid"] for p in status(name)["processes"] if p["id"] == "echo-1")
        relaunch = threading.Thread(target=apply_elsewhere, args=(name,),
                                    kwargs={"word": "beta"})
        relaunch.start()
        # echo is stopped; the slow one holds the relaunch until released
        wait_for(lambda: {p["id"]: p["state"] for p in status(name)["processes"]}
                 == {"echo-1": "exited", "slow-2": "stopping"}, timeout=60)
        waiting = subprocess.Popen([sys.executable, "-m", "tuilaunch", "wait", name, "echo-1",
                                    "running", "--timeout", "60"], stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True)
        try:
            # asked while echo-1 is stopped: it waits, connected, for the start
            wait_for(lambda: waiting.poll() is not None or _has_socket(waiting.pid),
                     what="the wait connected")
            assert waiting.poll() is None, waiting.communicate()
            release.touch()
            _, errors = waiting.communicate(timeout=90)
            assert waiting.returncode == 0, errors
        finally:
            if waiting.poll() is None:
                waiting.kill()
                waiting.wait()
        relaunch.join(60)
        echo = next(p for p in status(name)["processes"] if p["id"] == "echo-1")
        assert echo["state"] == "running" and echo["pid"] != old_pid
        assert "quick beta" in tl("logs", name, "echo-1").stdout
    finally:
        release.touch()  # a failed test's relaunch is not held up
        stop_here(name, gone_ok=True)
