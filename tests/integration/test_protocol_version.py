"""A client and a session server of different protocol versions say so in one line.

The server is real (the command line starts it, as a user would); only the version its
hello advertises is another, through `TUILAUNCH_TEST_PROTOCOL` (protocol.TEST_PROTOCOL_ENV,
read by the server for the tests only): "N" for a server of protocol N, "none" for one from
before versions (counted as protocol 1). The commands and the TUI run without it, as this
tuilaunch, locally and through a real sshd (`tuilaunch __proxy` relaying the socket).
"""

from __future__ import annotations

import json

import pytest

from tuilaunch import __version__
from tuilaunch.engine.run.session.protocol import PROTOCOL_VERSION, TEST_PROTOCOL_ENV

from ..conftest import run_cli, wait_for
from .sshd import Machine, Machines, machines_fixture  # noqa: F401
from .test_sessions import LAUNCH, Terminal, runtime, tl  # noqa: F401

OTHER = PROTOCOL_VERSION + 1


def mismatch(session: str, theirs: int, release: str | None = __version__) -> str:
    what = f"tuilaunch {release}" if release else "a tuilaunch from before protocol versions"
    return (f"session {session} speaks protocol {theirs} ({what}), this "
            f"tuilaunch speaks {PROTOCOL_VERSION} ({__version__}): use the same tuilaunch "
            "on both sides")


def start_speaking(write, advertised: str, env: dict[str, str] | None = None) -> str:
    """A detached session whose server advertises `advertised`; its name once it runs."""
    path = write(LAUNCH)
    started = run_cli(str(path), "--detach", env={**(env or {}), TEST_PROTOCOL_ENV: advertised})
    assert started.returncode == 0, started.stderr
    return started.stdout.strip()


def assert_one_line(done, line: str) -> None:
    assert done.returncode != 0
    assert "Traceback" not in done.stderr
    (said,) = done.stderr.splitlines()  # one line: `tuilaunch [COMMAND]: error: ` and it
    assert said.startswith("tuilaunch") and said.endswith(f"error: {line}"), said


def test_status_shows_the_protocol_of_the_session(runtime, write):  # noqa: F811
    name = tl(str(write(LAUNCH)), "--detach").stdout.strip()
    status = json.loads(tl("status", name, "--json").stdout)
    assert status["protocol"] == PROTOCOL_VERSION
    assert status["tuilaunch"] == __version__


@pytest.mark.parametrize("command", [
    ["status", "{name}"], ["status", "{name}", "--json"], ["logs", "{name}"],
    ["restart", "{name}", "ticker"], ["wait", "{name}", "ticker-1", "running"],
    ["topics", "{name}"], ["stop", "{name}"]])
def test_every_command_to_a_newer_server_says_both_versions(runtime, write,  # noqa: F811
                                                            command):
    name = start_speaking(write, str(OTHER))
    done = run_cli(*[part.format(name=name) for part in command])
    assert_one_line(done, mismatch(name, OTHER))


def test_a_server_from_before_versions_counts_as_protocol_1(runtime, write):  # noqa: F811
    name = start_speaking(write, "none")
    done = run_cli("status", name)
    assert_one_line(done, mismatch(name, 1, None))
    # ls lists it, as a session it cannot speak to, and says why
    listed = run_cli("ls")
    assert listed.returncode == 0
    assert name in listed.stdout
    assert f"tuilaunch: {mismatch(name, 1, None)}" in listed.stderr.splitlines()


def test_the_tui_does_not_attach_to_another_version(runtime, write):  # noqa: F811
    name = start_speaking(write, str(OTHER))
    terminal = Terminal("attach", name)
    try:
        assert terminal.wait_exit() != 0
    finally:
        terminal.close()
    screen = terminal.screen.decode(errors="replace")
    assert mismatch(name, OTHER) in screen.replace("\r\n", " ").replace("\n", " ")
    assert "Traceback" not in screen


def test_the_tui_of_a_launch_stops_at_a_server_of_another_version(runtime, write,  # noqa: F811
                                                                   monkeypatch):
    """`tuilaunch FILE` starts its own server; one speaking another protocol (as a server
    found under the launch's name could) is refused with the line, and stopped."""
    monkeypatch.setenv(TEST_PROTOCOL_ENV, str(OTHER))  # for the server it starts
    terminal = Terminal(str(write(LAUNCH)))
    try:
        assert terminal.wait_exit() != 0
    finally:
        terminal.close()
    screen = terminal.screen.decode(errors="replace").replace("\r\n", " ")
    assert "speaks protocol" in screen and "use the same tuilaunch on both sides" in screen
    assert "Traceback" not in screen
    # the server it started, which it cannot speak to, is stopped with what it started
    wait_for(lambda: "no running sessions" in run_cli("ls").stdout)


def there(machine: Machine, **extra: str) -> dict[str, str]:
    return {"XDG_RUNTIME_DIR": str(machine.runtime),
            "ROS_LOG_DIR": str(machine.folder / "roslog"), **extra}


def test_over_ssh_the_commands_and_the_tui_say_both_versions(machines: Machines,
                                                             write):
    robot = machines["robot1"]
    path = write(LAUNCH)
    started = run_cli(str(path), "--detach", "--name", "far",
                      env=there(robot, **{TEST_PROTOCOL_ENV: str(OTHER)}))
    assert started.returncode == 0, started.stderr
    for command in (["status", "robot1:far"], ["logs", "robot1:far"], ["stop", "robot1:far"]):
        assert_one_line(run_cli(*command), mismatch("robot1:far", OTHER))
    terminal = Terminal("attach", "robot1:far")
    try:
        assert terminal.wait_exit() != 0
    finally:
        terminal.close()
    screen = terminal.screen.decode(errors="replace").replace("\r\n", " ")
    assert mismatch("robot1:far", OTHER) in screen
