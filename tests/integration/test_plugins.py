"""What plugs into a launch from above `run`: a plugin's hooks, session requests and events."""

from __future__ import annotations

import asyncio
import tempfile
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import Any

import pytest

from tuilaunch.engine.plan.model import ProcessPlan
from tuilaunch.engine.plan.session import Session
from tuilaunch.engine.run.events import Event, Log
from tuilaunch.engine.run.plugins import Clients, Handlers, Plugin
from tuilaunch.engine.run.session import session_dir
from tuilaunch.engine.run.session.protocol import decode, encode
from tuilaunch.engine.run.session.session_server import SessionServer
from tuilaunch.engine.run.supervisor.supervisor import Supervisor
from tuilaunch.engine.run.vocabulary.request import Request
from tuilaunch.engine.run.vocabulary.requests import Status

from ..conftest import python_prints

LAUNCH = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(cmd=['sleep', '600'], name='steady'))
    return sl.launch_description()
"""


def test_the_run_layer_loads_without_ros_and_the_engine_without_textual():
    probe = ("import sys, tuilaunch.engine.run.supervisor.supervisor\n"
             "import tuilaunch.engine.run.session.session_server\n"
             "import tuilaunch.engine.launcher, tuilaunch.engine.server_main\n"
             "print(sorted({m.split('.')[0] if m.startswith('textual') else m\n"
             "  for m in sys.modules if m.startswith(('textual', 'tuilaunch.engine.ros'))}))")
    run_only = ("import sys, tuilaunch.engine.run.supervisor.supervisor\n"
                "import tuilaunch.engine.run.session.session_server\n"
                "print([m for m in sys.modules if m.startswith('tuilaunch.engine.ros')])")
    assert python_prints(run_only, timeout=60).strip() == "[]"
    wired = python_prints(probe, timeout=60)
    assert "textual" not in wired  # the wired engine has ROS, never Textual
    assert "tuilaunch.engine.ros.lifecycle" in wired


@dataclass(frozen=True)
class Greet(Request[dict[str, Any]], op="greet"):
    """A plugin's own request: its class names its op, as the session's requests do."""

    process: str


@dataclass(frozen=True)
class Whisper(Request[dict[str, Any]], op="whisper"):
    pass


class Greeter(Plugin):
    """Follows the processes that start and answers `greet` with an event to every client."""

    def __init__(self, supervisor: Supervisor) -> None:
        self.supervisor = supervisor
        self.started: list[str] = []

    def process_started(self, proc: ProcessPlan) -> Awaitable[Any] | None:
        self.started.append(proc.id)
        return None

    def snapshot(self) -> dict[str, Any]:
        return {"greeted": list(self.started)}

    def handlers(self, find_process: Callable[[str], str]) -> Handlers:
        async def greet(request: Greet, client: int) -> Any:
            process = find_process(request.process)
            self.supervisor.emit(Log(process, reason=f"hello {process}"))
            return {"greeted": process}

        return {Greet: greet}


def test_a_plugin_answers_its_own_request_and_reaches_every_client(write, tmp_path,
                                                                    monkeypatch):
    monkeypatch.setenv("XDG_RUNTIME_DIR", tempfile.mkdtemp(prefix="tl"))  # short socket path
    session = Session(str(write(LAUNCH)), {}, tmp_path / "params")
    supervisor = Supervisor(session.plan, tmp_path / "log", sigterm_timeout=3)
    greeter = Greeter(supervisor)
    supervisor.add_plugin(greeter)
    server = SessionServer("plugged", session, tmp_path / "log", supervisor=supervisor)
    with pytest.raises(ValueError, match="already answered"):
        server.add_handler(Status, greeter.handlers(server.find_process)[Greet])

    async def scenario() -> None:
        serving = asyncio.ensure_future(server.serve())
        deadline = asyncio.get_running_loop().time() + 30
        while greeter.started != ["steady-1"] or not session_dir.socket_path("plugged").exists():
            assert asyncio.get_running_loop().time() < deadline, "never started"
            await asyncio.sleep(0.05)
        reader, writer = await asyncio.open_unix_connection(
            str(session_dir.socket_path("plugged")))
        assert decode(await reader.readline())["type"] == "hello"
        writer.write(encode({"id": 1, "op": "subscribe"}))
        subscribed = decode(await reader.readline())
        assert subscribed["result"]["greeted"] == ["steady-1"]
        writer.write(encode({"id": 2, "op": "greet", "process": "steady"}))
        writer.write(encode({"id": 3, "op": "greet", "process": "nobody"}))
        replies: dict[int, dict[str, Any]] = {}
        logged: list[str] = []
        while len(replies) < 2 or not logged:
            message = decode(await asyncio.wait_for(reader.readline(), 30))
            if message["type"] == "reply":
                replies[message["id"]] = message
            elif message["type"] == "events":
                logged += [e["reason"] for e in message["events"] if e["kind"] == "log"]
        assert replies[2]["result"] == {"greeted": "steady-1"}
        assert not replies[3]["ok"] and "no process 'nobody'" in replies[3]["error"]
        assert logged == ["hello steady-1"]
        writer.write(encode({"id": 4, "op": "shutdown"}))
        assert await asyncio.wait_for(serving, 30) == 0
        writer.close()

    asyncio.run(scenario())
    assert supervisor.states["steady-1"] == "exited"



class Whisperer(Plugin):
    """Answers `whisper` with an event to the asking client only; notes who leaves."""

    def __init__(self) -> None:
        self.clients: Clients | None = None
        self.asked: list[int] = []
        self.gone: list[int] = []

    def serve(self, clients: Clients) -> None:
        self.clients = clients

    def client_gone(self, client: int) -> None:
        self.gone.append(client)

    def handlers(self, find_process: Callable[[str], str]) -> Handlers:
        async def whisper(request: Whisper, client: int) -> Any:
            assert self.clients is not None
            self.asked.append(client)
            self.clients.send(Event("whisper", reason=f"to {client}"), client)
            return {"subscribed": self.clients.subscribed(client)}

        return {Whisper: whisper}


def test_a_plugin_streams_to_the_client_that_asked_and_hears_when_it_leaves(
        write, tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_RUNTIME_DIR", tempfile.mkdtemp(prefix="tl"))  # short socket path
    session = Session(str(write(LAUNCH)), {}, tmp_path / "params")
    supervisor = Supervisor(session.plan, tmp_path / "log", sigterm_timeout=3)
    whisperer = Whisperer()
    supervisor.add_plugin(whisperer)
    server = SessionServer("streams", session, tmp_path / "log", supervisor=supervisor)

    async def connect() -> tuple[asyncio.StreamReader, asyncio.StreamWriter]:
        reader, writer = await asyncio.open_unix_connection(
            str(session_dir.socket_path("streams")))
        assert decode(await reader.readline())["type"] == "hello"
        writer.write(encode({"id": 1, "op": "subscribe", "kinds": ["whisper"]}))
        assert decode(await reader.readline())["ok"]
        return reader, writer

    async def whisper(reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                      request: int) -> list[str]:
        """Whispers (claiming to be client 99); what it hears until the reply and at least
        one whisper came (in either order)."""
        writer.write(encode({"id": request, "op": "whisper", "client": 99}))
        heard: list[str] = []
        replied = False
        while not (replied and heard):
            message = decode(await asyncio.wait_for(reader.readline(), 30))
            if message["type"] == "events":
                assert {e["kind"] for e in message["events"]} == {"whisper"}  # kinds filter
                heard += [e["reason"] for e in message["events"]]
            elif message["type"] == "reply" and message["id"] == request:
                assert message["result"] == {"subscribed": True}
                replied = True
        return heard

    async def scenario() -> None:
        serving = asyncio.ensure_future(server.serve())
        deadline = asyncio.get_running_loop().time() + 30
        while supervisor.states.get("steady-1") != "running" or \
                not session_dir.socket_path("streams").exists():
            assert asyncio.get_running_loop().time() < deadline, "never started"
            await asyncio.sleep(0.05)
        first, first_writer = await connect()
        second, second_writer = await connect()
        heard = await whisper(first, first_writer, 2)
        (me,) = whisperer.asked
        assert me != 99  # the server says who really asks
        assert heard == [f"to {me}"]
        heard = await whisper(second, second_writer, 2)
        other = whisperer.asked[1]
        assert other != me
        assert heard == [f"to {other}"]  # never the first client's whisper
        first_writer.close()
        deadline = asyncio.get_running_loop().time() + 30
        while whisperer.gone != [me]:
            assert asyncio.get_running_loop().time() < deadline, "client_gone never came"
            await asyncio.sleep(0.05)
        second_writer.write(encode({"id": 3, "op": "shutdown"}))
        assert await asyncio.wait_for(serving, 30) == 0
        second_writer.close()

    asyncio.run(scenario())
