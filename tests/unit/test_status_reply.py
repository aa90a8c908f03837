"""`status`'s reply as dataclasses (vocabulary/status.py): the server builds a StatusReply,
the one codec (vocabulary/request.py) writes it as the wire's JSON, and every client reads
it back as the same StatusReply; `status --json` prints the JSON the untyped server sent,
key for key, so the scripts that read it read what they always did."""

from __future__ import annotations

import asyncio
import json
from pathlib import Path
from typing import Any

import pytest

from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.session.protocol import decode, encode
from tuilaunch.engine.run.session.session_server import SessionServer
from tuilaunch.engine.run.vocabulary.request import MalformedReply, reply_to_json
from tuilaunch.engine.run.vocabulary.requests import Status
from tuilaunch.engine.run.vocabulary.status import (
    ActionStatus,
    PlacementInfo,
    ProcessStatus,
    StatusReply,
    Typing,
)

LAUNCH = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess, LogInfo, SetEnvironmentVariable


def generate_launch_description():
    return LaunchDescription([
        SetEnvironmentVariable("TL_STATUS", "1"),
        ExecuteProcess(cmd=["sleep", "30"], name="napper"),
        LogInfo(msg="said"),
    ])
"""

SESSION_KEYS = ["name", "file", "command", "arguments", "pid", "started", "log_dir",
                "file_stamp", "protocol", "tuilaunch", "counts", "processes", "actions",
                "dropped_clients", "typing"]
"""What a script reads in `status --json`, in the order the untyped server wrote it."""
PROCESS_KEYS = ["id", "name", "state", "pid", "exit_code", "detail", "machine",
                "cpu_percent", "rss_bytes", "threads", "command", "command_line", "env",
                "unset_env", "terminal"]


def over_the_wire(result: Any) -> dict[str, Any]:
    """A reply's result as a client reads it off the socket (protocol.py's encoding)."""
    message = decode(encode({"type": "reply", "id": 1, "ok": True, "result": result}))
    read: dict[str, Any] = message["result"]
    return read


def every_field() -> StatusReply:
    """A status with each field away from its default, nested ones too."""
    return StatusReply(
        name="base", file="/robot/bringup.py", command=["bringup.py"],
        arguments={"robot": "r1"}, pid=4242, started=1700000000.5, log_dir="/tmp/logs",
        file_stamp=[1700000000123456789, 512], protocol=7, tuilaunch="1.2.3",
        placement=PlacementInfo(text="nuc: {host: nuc}", path="/robot/machines.yaml",
                                share="nuc"),
        counts={"running": 1, "failed": 1},
        processes=[
            ProcessStatus(id="talker-1", name="/r1/talker", state="running", pid=4300,
                          machine="nuc", cpu_percent=12.5, rss_bytes=1 << 24, threads=9,
                          command=["/opt/talker", "--ros-args"],
                          command_line="cd /tmp && env -u GONE -- /opt/talker --ros-args",
                          env={"A": "1"}, unset_env=["GONE"], terminal=True),
            ProcessStatus(id="crashy-2", name="/crashy", state="failed", exit_code=-11,
                          detail="died of SIGSEGV", command=["/opt/crashy"],
                          command_line="/opt/crashy", env={}, unset_env=[], terminal=False,
                          signal="SIGSEGV", core="/var/crash/core.4301")],
        actions=[ActionStatus(id="log-3", kind="log", state="done")],
        dropped_clients=2, typing=Typing(client=3, process="talker-1"))


def test_every_field_comes_back_as_the_server_built_it() -> None:
    built = every_field()
    wire = over_the_wire(reply_to_json(built))
    read = Status().reply(wire)
    assert read == built
    assert read.processes[1].signal == "SIGSEGV" and read.typing == Typing(3, "talker-1")
    assert read.placement is not None and read.placement.share == "nuc"
    # what `status --json` prints is the wire, byte for byte
    assert json.dumps(read.to_json(), indent=2) == json.dumps(wire, indent=2)


async def test_the_servers_status_reads_back_whole_and_prints_as_it_was_sent(
        write: Any, tmp_path: Path) -> None:
    session = Session(str(write(LAUNCH)), {"robot": "r1"}, tmp_path / "params")
    server = SessionServer("typed", session, tmp_path / "log")
    sent = over_the_wire(await asyncio.wait_for(server._perform(Status(resources=False), 1),
                                                30))
    read = Status(resources=False).reply(sent)
    assert read == server.status()
    assert list(sent) == SESSION_KEYS  # scripts read these keys, in this order
    assert list(sent["processes"][0]) == PROCESS_KEYS
    assert json.dumps(read.to_json(), indent=2) == json.dumps(sent, indent=2)
    napper = read.process("napper-1")
    assert napper is not None and napper.state == "pending" and napper.pid is None
    assert napper.command is not None and napper.command[-2:] == ["sleep", "30"]
    assert napper.env is not None and napper.env["TL_STATUS"] == "1"
    assert napper.terminal is False
    assert napper.signal is None and "signal" not in sent["processes"][0]
    assert read.actions == [ActionStatus(id=read.actions[0].id, kind="log", state="pending")]
    assert read.counts == {"pending": 1} and read.typing is None
    assert read.name == "typed" and read.arguments == {"robot": "r1"}
    assert read.log_dir == str(tmp_path / "log") and read.started == server.started


def test_a_newer_servers_fields_are_ignored() -> None:
    wire = reply_to_json(every_field())
    wire["uptime"] = 12.0
    wire["processes"][0]["gpu_percent"] = 40.0
    wire["typing"]["since"] = 3.5
    assert Status().reply(wire) == every_field()


def test_a_field_the_reply_lacks_takes_its_default_and_stays_out_of_the_json() -> None:
    read = Status().reply({"name": "old", "processes": [{"id": "talker-1"}]})
    assert read.placement is None and read.typing is None and read.counts == {}
    talker = read.processes[0]
    assert (talker.state, talker.pid, talker.command, talker.terminal, talker.signal) == \
        ("pending", None, None, None, None)
    printed = read.processes[0].to_json()
    # unknown, so unsaid: a script's `"command" in p` still means the command is known
    assert not {"command", "command_line", "env", "unset_env", "terminal", "signal",
                "core"} & set(printed)
    assert "placement" not in read.to_json() and "protocol" not in read.to_json()


def test_a_placed_process_whose_terminal_is_not_known_says_null() -> None:
    """Its machine knows its terminal: not answering, the launching side writes null (as
    the untyped server did), where a process here with no command has no terminal key."""
    placed = ProcessStatus(id="far-1", machine="nuc")
    assert placed.to_json()["terminal"] is None
    assert placed.started_with() == {"terminal": None}
    known = every_field().processes[0]
    assert known.started_with() == {
        "command": ["/opt/talker", "--ros-args"],
        "command_line": "cd /tmp && env -u GONE -- /opt/talker --ros-args",
        "env": {"A": "1"}, "unset_env": ["GONE"], "terminal": True}


@pytest.mark.parametrize(("result", "said"), [
    ({"processes": [{"name": "/talker"}]}, "a ProcessStatus needs id"),
    ({"typing": {"process": "talker-1"}}, "a Typing needs client"),
    (["not", "an", "object"], "a StatusReply must be an object, not ['not', 'an', "
                              "'object']"),
])
def test_a_reply_that_cannot_be_read_is_one_line(result: Any, said: str) -> None:
    with pytest.raises(MalformedReply) as refused:
        Status().reply(result)
    assert str(refused.value) == said
