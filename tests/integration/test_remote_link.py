"""Sessions on other machines: the ssh link to a real session through a real sshd.

"robot1" and "robot2" are sshd servers on 127.0.0.1 (tests/integration/sshd.py), each with its own
session folder; a session "on robot1" is started with robot1's folder, as a user logged in
there would start it, and reached only through `ssh robot1 ... __proxy NAME`.
"""

from __future__ import annotations

import asyncio
import json
import os
import shlex
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tuilaunch.engine.plan.machines import Machine as Machine_
from tuilaunch.engine.run.machines.proxy import CHUNK
from tuilaunch.engine.run.machines.remote import (
    Address,
    RemoteError,
    list_remote,
    open_remote_connection,
    open_remote_link,
    parse_address,
    run_remote,
    ssh_argv,
)
from tuilaunch.engine.run.session.protocol import decode, encode
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.engine.run.vocabulary.request import Request, to_message
from tuilaunch.engine.run.vocabulary.requests import Status

from ..conftest import run_cli, wait_for
from .session_steps import start_here, stop_here
from .sshd import Machine, Machines, alive, free_port, keygen, proxies_on
from .test_remote_sessions import logged_in
from .test_sessions import wait_state

LAUNCH = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(name='ticker', cmd=[
        'sh', '-c', 'i=0; while true; do i=$((i+1)); echo tick $i; sleep 0.1; done']))
    return sl.launch_description()
"""


def start_on(machine: Machine, path: Path, name: str) -> None:
    """A session of the launch file `path` started on `machine` (its session folder), as a
    user there would (from this process: the link to it is the subject)."""
    with logged_in(machine):
        start_here(path, "--name", name)
        wait_state(name, "ticker-1", "running", timeout=30)


@pytest.fixture(name="machines", scope="module")
def machines_fixture(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Machines]:
    """robot1 and robot2 for the whole module, reachable through `TUILAUNCH_SSH_COMMAND`:
    the tests ask them and leave them as they were (a session a test starts, it stops)."""
    fleet = Machines(tmp_path_factory.mktemp("link") / "ssh")
    try:
        with pytest.MonkeyPatch.context() as patch:
            for key, value in fleet.env().items():
                patch.setenv(key, value)
            yield fleet
    finally:
        fleet.stop()  # whatever runs under robot1 and robot2 ends with them


@pytest.fixture(scope="module")
def far(machines: Machines, tmp_path_factory: pytest.TempPathFactory) -> str:
    """The session "far" on robot1, for the tests that only talk to it (and their links):
    the only session there."""
    path = tmp_path_factory.mktemp("far") / "test_launch.py"
    path.write_text(LAUNCH)
    start_on(machines["robot1"], path, "far")
    return "far"


def request(sock, asked: Request, request_id: int = 1) -> dict:
    """The whole reply message to `asked`, read off the raw socket."""
    sock.sendall(encode(to_message(asked, request_id)))
    op = asked.op
    reader = sock.makefile("rb")
    try:
        while True:
            line = reader.readline()
            assert line, f"the link closed before the reply to {op}"
            message = decode(line)
            if message.get("type") == "reply" and message.get("id") == request_id:
                return message
    finally:
        reader.close()


# --- addresses --------------------------------------------------------------------------------

def test_addresses_name_a_host_or_this_machine():
    assert parse_address("demo") == Address(None, "demo")
    assert parse_address("robot1:demo") == Address("robot1", "demo")
    assert parse_address("ops@robot1.local:demo-2") == Address("ops@robot1.local", "demo-2")
    assert parse_address("[fe80::1%eth0]:demo") == Address("fe80::1%eth0", "demo")
    assert str(parse_address("[::1]:demo")) == "[::1]:demo"
    assert str(parse_address("robot1:demo")) == "robot1:demo"


@pytest.mark.parametrize("text, says", [
    (":demo", "no host before ':'"),
    ("fe80::1:demo", "in brackets"),
    ("-oProxyCommand=touch /tmp/x:demo", "is not a host name"),
    ("robot1:", "not usable"),
    ("robot1:a/b", "not usable"),
    ("[::1]demo", "is not [HOST]:NAME"),
])
def test_bad_addresses_are_one_line(text, says):
    with pytest.raises(SessionError) as caught:
        parse_address(text)
    assert says in str(caught.value)


def test_ssh_command_comes_from_the_environment_and_quotes_for_the_remote_shell():
    argv = ssh_argv("robot1", ["__proxy", "demo"], {
        "TUILAUNCH_SSH_COMMAND": "ssh -F '/my config' -p 2222",
        "TUILAUNCH_REMOTE": "/opt/venv/bin/tuilaunch"})
    assert argv[:4] == ["ssh", "-F", "/my config", "-p"]
    assert "BatchMode=yes" in argv and "-T" in argv
    assert argv[-2:] == ["robot1", "/opt/venv/bin/tuilaunch __proxy demo"]


def test_remote_words_reach_the_remote_program_intact(machines):
    words = ["two words", "$HOME", "a;b", "it's"]
    environ = {**os.environ, "TUILAUNCH_REMOTE": "printf '%s\\n'"}
    out = run_remote("robot1", words, environ=environ)
    assert out.splitlines() == words


# --- the link ---------------------------------------------------------------------------------

def test_a_session_on_robot1_answers_over_ssh_and_closing_the_link_stops_nothing(
        machines, far):
    link = open_remote_link("robot1", "far")
    try:
        assert link.info["name"] == "far"
        reply = request(link.sock, Status())
        assert reply["ok"], reply
        states = {p["id"]: p["state"] for p in reply["result"]["processes"]}
        assert states == {"ticker-1": "running"}
        server = reply["result"]["pid"]
    finally:
        link.close()
    assert link.process.returncode is not None  # ssh ended with the link
    wait_for(lambda: not proxies_on(machines["robot1"]))  # and the proxy there
    assert alive(server)  # the session runs on
    again = open_remote_link("robot1", "far")
    try:
        assert request(again.sock, Status())["result"]["counts"] == {"running": 1}
    finally:
        again.close()


async def test_events_stream_over_the_link(machines, far):
    link, conn = await open_remote_connection("robot1", "far")
    reader, writer = conn.reader, conn.writer  # the raw lines, read here
    try:
        writer.write(encode({"id": 1, "op": "subscribe"}))
        await writer.drain()
        seen: list[str] = []
        deadline = time.monotonic() + 30
        while not any(line.startswith("tick") for line in seen):
            assert time.monotonic() < deadline, "no output crossed the link"
            message = decode(await asyncio.wait_for(reader.readline(), 30))
            for event in message.get("events") or []:
                seen.extend(event.get("lines") or [])
    finally:
        writer.close()
        await asyncio.get_running_loop().run_in_executor(None, link.close)


def test_sessions_are_listed_per_machine_as_ls_json(machines, far):
    listed = list_remote("robot1")
    local = json.loads(run_cli("ls", "--json", env={
        "XDG_RUNTIME_DIR": str(machines["robot1"].runtime)}).stdout)
    assert [s["name"] for s in listed] == ["far"]
    assert [sorted(s) for s in listed] == [sorted(s) for s in local]
    assert listed[0]["pid"] == local[0]["pid"]
    assert list_remote("robot2") == []


def test_the_relay_is_ssh_and_the_proxy_alone(machines, far):
    """What the TUI will run, by hand: `ssh robot1 <tuilaunch> __proxy NAME`."""
    argv = [*shlex.split(machines.ssh_command), "robot1",
            f"{os.environ['TUILAUNCH_REMOTE']} __proxy far"]
    proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE)
    try:
        assert proc.stdin is not None and proc.stdout is not None
        assert decode(proc.stdout.readline())["type"] == "hello"
        proc.stdin.write(encode({"id": 7, "op": "find", "process": "ticker"}))
        proc.stdin.flush()
        reply = decode(proc.stdout.readline())
        assert reply == {"type": "reply", "id": 7, "ok": True, "result": "ticker-1"}
        proc.stdin.close()  # the client hangs up: the relay ends
        assert proc.wait(timeout=30) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


# --- failures, each one line naming the machine ---------------------------------------------

def _ssh_config(machines: Machines, text: str) -> dict[str, str]:
    config = machines.folder / "other_config"
    config.write_text(text)
    return {**os.environ, "TUILAUNCH_SSH_COMMAND": f"ssh -F {config}"}


def _one_line(error: BaseException) -> str:
    return str(error).split("\n  hint:", 1)[0]


def test_an_unreachable_machine_is_named(machines):
    environ = _ssh_config(machines, machines.host_entry("deadbox", free_port()))
    with pytest.raises(RemoteError) as caught:
        open_remote_link("deadbox", "far", environ=environ)
    line = _one_line(caught.value)
    assert line.startswith("cannot reach deadbox: ") and "Connection refused" in line, line
    assert "\n" not in line


def test_a_refused_key_is_said(machines, tmp_path):
    stranger = tmp_path / "stranger_key"
    keygen(stranger)
    environ = _ssh_config(machines, machines.host_entry(
        "robot1", machines["robot1"].port, key=stranger))
    with pytest.raises(RemoteError) as caught:
        open_remote_link("robot1", "far", environ=environ)
    line = _one_line(caught.value)
    assert line.startswith("robot1 refused the login") and "Permission denied" in line, line
    assert "without a prompt" in str(caught.value)


def test_a_missing_remote_tuilaunch_is_said(machines):
    environ = {**os.environ, "TUILAUNCH_REMOTE": "/nonexistent/tuilaunch"}
    with pytest.raises(RemoteError) as caught:
        open_remote_link("robot1", "far", environ=environ)
    assert _one_line(caught.value).startswith(
        "robot1: tuilaunch not found there (/nonexistent/tuilaunch"), str(caught.value)
    with pytest.raises(RemoteError) as caught:
        list_remote("robot1", environ=environ)
    assert "tuilaunch not found there" in str(caught.value)


def test_an_unknown_session_is_said_with_the_ones_there(machines, far):
    # the links earlier tests closed are gone: none is left for the check at the end
    wait_for(lambda: not proxies_on(machines["robot1"]))
    with pytest.raises(RemoteError) as caught:
        open_remote_link("robot1", "near")
    assert _one_line(caught.value) == "robot1: no running session named near"
    with pytest.raises(RemoteError) as caught:
        open_remote_link("robot2", "far")
    assert _one_line(caught.value) == "robot2: no running session named far"
    assert not proxies_on(machines["robot1"])



# --- machines of a machines file ------------------------------------------------------------

def test_a_machine_sources_its_setup_and_sets_its_env_before_its_tuilaunch(machines, tmp_path):
    setup = tmp_path / "setup with space.bash"
    setup.write_text("export FROM_SETUP=sourced\n")
    program = tmp_path / "fake_tuilaunch"  # stands for the machine's tuilaunch: says its env
    program.write_text('#!/bin/sh\nprintf "%s|%s|%s\\n" "$FROM_SETUP" "$FROM_ENV" "$*"\n')
    program.chmod(0o755)
    nuc = Machine_("nuc", "robot1", str(program), str(setup), {"FROM_ENV": "a b'c"})
    out = run_remote(nuc, ["__ls", "x y"])
    assert out == "sourced|a b'c|__ls x y\n"


def test_a_machine_is_named_in_its_failures(machines, tmp_path):
    nuc = Machine_("nuc", "robot1", "/nonexistent/tuilaunch")
    with pytest.raises(RemoteError) as caught:
        open_remote_link(nuc, "far")
    assert _one_line(caught.value).startswith(
        "nuc (robot1): tuilaunch not found there (/nonexistent/tuilaunch"), str(caught.value)
    broken = Machine_("nuc", "robot1", None, str(tmp_path / "missing_setup.bash"))
    with pytest.raises(RemoteError) as caught:
        list_remote(broken)
    assert _one_line(caught.value).startswith(
        "nuc (robot1): its setup file cannot be sourced"), str(caught.value)


def test_a_dropped_link_stops_nothing_and_says_why(machines, far):
    link = open_remote_link("robot1", "far")
    try:
        server = link.info["pid"]
        wait_for(lambda: proxies_on(machines["robot1"]))
        for pid in proxies_on(machines["robot1"]):
            os.kill(pid, signal.SIGKILL)  # the far end dies (as with a dropped connection)
        link.sock.settimeout(30)
        assert link.sock.recv(1) == b""  # the client sees the link end
        assert link.lost_reason().startswith("lost the link to robot1 (")
    finally:
        link.close()
    assert alive(server)
    again = open_remote_link("robot1", "far")  # and can come back
    try:
        assert request(again.sock, Status())["result"]["pid"] == server
    finally:
        again.close()


# --- the proxy on its own -------------------------------------------------------------------

@pytest.mark.parametrize("args, says", [
    (["__proxy", "nosuch"], "tuilaunch: error: no running session named nosuch"),
    (["__proxy", "a/b"], "tuilaunch: error: session name 'a/b' is not usable"),
    (["__proxy"], "usage: tuilaunch __proxy NAME"),
])
def test_the_proxy_fails_with_one_line(args, says, tmp_path):
    runtime = tmp_path / "run"
    runtime.mkdir(mode=0o700)
    done = subprocess.run([sys.executable, "-m", "tuilaunch.engine.run.machines.proxy", *args],
                          capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL,
                          env={**os.environ, "XDG_RUNTIME_DIR": str(runtime)})
    assert done.returncode == 2
    assert done.stderr.startswith(says), done.stderr
    assert "Traceback" not in done.stderr and done.stdout == ""


def test_a_session_started_through_ssh_is_ended_with_its_machine(tmp_path, write):
    """The machines' teardown leaves nothing: a session started over ssh (its server
    detached from ssh, re-parented away) ends with the machine, nodes included."""
    fleet = Machines(tmp_path / "fleet", aliases=("robot9",))
    try:
        path = write(LAUNCH)
        environ = {**os.environ, **fleet.env(
            TUILAUNCH_REMOTE=f"{shlex.quote(sys.executable)} -m tuilaunch")}
        name = run_remote("robot9", [str(path), "--detach", "--name", "left"],
                          environ=environ, timeout=60).strip()
        assert name == "left"
        listed = list_remote("robot9", environ={**os.environ, **fleet.env()})
        server = listed[0]["pid"]
        wait_for(lambda: _children(server))
        nodes = _children(server)
        sshd = fleet["robot9"].proc
    finally:
        fleet.stop()
    assert sshd.poll() is not None
    assert not alive(server) and not any(alive(p) for p in nodes)


def _children(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        try:
            if int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
        except (OSError, IndexError, ValueError):
            continue
    return found


BIG = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(name='big', cmd=[
        'sh', '-c', 'while true; do head -c 300000 /dev/zero | tr "\\\\0" x; echo; sleep 0.3; '
        'done']))
    return sl.launch_description()
"""


async def test_a_message_larger_than_the_relay_chunk_crosses_whole(machines, write):
    """Another session on robot1 beside "far", stopped at the end."""
    path = write(BIG, "big_launch.py")
    with logged_in(machines["robot1"]):
        start_here(path, "--name", "big")
    try:
        await big_line_crosses_whole()
    finally:
        with logged_in(machines["robot1"]):
            stop_here("big")  # robot1 runs "far" alone again


async def big_line_crosses_whole() -> None:
    link, conn = await open_remote_connection("robot1", "big")
    reader, writer = conn.reader, conn.writer  # the raw lines, read here
    try:
        writer.write(encode({"id": 1, "op": "subscribe"}))
        await writer.drain()
        deadline = time.monotonic() + 30
        text, biggest = "", 0
        while len(text) < 300000:  # the reader cuts a line at 64 KiB; the pieces all come
            assert time.monotonic() < deadline, "the big line never crossed"
            raw = await asyncio.wait_for(reader.readline(), 30)
            biggest = max(biggest, len(raw))
            message = decode(raw)  # whole JSON: no byte lost or doubled by the relay
            for event in message.get("events") or []:
                text += "".join(event.get("lines") or [])
        assert set(text) == {"x"}
        assert biggest > CHUNK  # a message the proxy relayed in several reads
    finally:
        writer.close()
        await asyncio.get_running_loop().run_in_executor(None, link.close)
