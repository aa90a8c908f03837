"""The one connection (engine/run/session/connection.py) and its reconnector, over a real
socketpair with a scripted server on the other end: the greeting checked once (another
version is one line), replies matched by id whatever their order, events handed to the
follower, and a dropped link reconnected with its attempts counted."""

from __future__ import annotations

import asyncio
import json
import socket
import time
from typing import Any

import pytest

from tuilaunch.engine.run.session.connection import Connection
from tuilaunch.engine.run.session.protocol import (
    MAX_MESSAGE,
    PROTOCOL_VERSION,
    VersionMismatch,
    greet,
)
from tuilaunch.engine.run.session.reconnector import Reconnector
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.engine.run.vocabulary.requests import Find, Status, StatusReply

HELLO = {"type": "hello", "info": {"protocol": PROTOCOL_VERSION, "log_dir": "/tmp"}}


class Server:
    """The server's end of a socketpair: lines written, requests read back."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.file = sock.makefile("rb")

    def say(self, *messages: dict[str, Any]) -> None:
        self.sock.sendall(b"".join(json.dumps(m).encode() + b"\n" for m in messages))

    def hang_up(self) -> None:
        self.file.close()
        self.sock.close()

    def heard(self) -> dict[str, Any]:
        return dict(json.loads(self.file.readline()))


async def connected(hello: dict[str, Any] = HELLO) -> tuple[Connection, Server]:
    ours, theirs = socket.socketpair()
    server = Server(theirs)
    server.say(hello)
    reader, writer = await asyncio.open_connection(sock=ours, limit=MAX_MESSAGE)
    # the greeting read and checked as every client does
    return await Connection.greeted(reader, writer, "far", 5.0), server


async def test_another_protocol_is_one_line_naming_both_versions() -> None:
    old = {"type": "hello", "info": {"protocol": 1, "tuilaunch": "0.1.0"}}
    with pytest.raises(VersionMismatch) as caught:
        await connected(old)
    said = str(caught.value)
    assert "\n" not in said
    assert said.startswith("session far speaks protocol 1 (tuilaunch 0.1.0), this tuilaunch "
                           f"speaks {PROTOCOL_VERSION}")


def test_a_line_that_is_no_greeting_says_so() -> None:
    with pytest.raises(SessionError, match=r"^session far did not greet$"):
        greet(b"", "far")
    with pytest.raises(SessionError, match=r"^session far did not greet$"):
        greet(b'{"type": "reply", "id": 1}\n', "far")
    assert greet(json.dumps(HELLO).encode(), "far")["log_dir"] == "/tmp"


async def test_replies_are_matched_by_id_out_of_order_and_events_reach_the_follower() -> None:
    conn, server = await connected()
    assert conn.info["log_dir"] == "/tmp"
    loop = asyncio.get_running_loop()
    got: list[dict[str, Any]] = []

    async def follow() -> None:
        while (message := await conn.receive()) is not None:
            got.append(message)

    follower = asyncio.ensure_future(follow())
    status = asyncio.ensure_future(conn.ask(Status()))
    find = asyncio.ensure_future(conn.ask(Find("talker")))
    asked = [await loop.run_in_executor(None, server.heard) for _ in range(2)]
    assert [(m["op"], m["id"]) for m in asked] == [("status", 1), ("find", 2)]
    # the second answered first, an event between them
    server.say({"type": "reply", "id": 2, "ok": True, "result": "talker-1"},
               {"type": "events", "events": [{"kind": "started", "process": "talker-1"}]},
               {"type": "reply", "id": 1, "ok": True, "result": {"processes": []}})
    assert await asyncio.wait_for(find, 5) == "talker-1"
    assert await asyncio.wait_for(status, 5) == StatusReply()  # read as its reply type
    refused = asyncio.ensure_future(conn.ask(Find("nobody")))
    await loop.run_in_executor(None, server.heard)
    server.say({"type": "reply", "id": 3, "ok": False, "error": "no process nobody"})
    with pytest.raises(SessionError, match=r"^session far: no process nobody$"):
        await asyncio.wait_for(refused, 5)
    server.hang_up()
    await asyncio.wait_for(follower, 5)
    assert got == [{"type": "events", "events": [{"kind": "started", "process": "talker-1"}]}]
    conn.close()


async def test_a_call_reads_its_own_reply_and_keeps_what_came_before_it() -> None:
    conn, server = await connected()
    loop = asyncio.get_running_loop()
    call = asyncio.ensure_future(conn.call(Find("talker")))
    await loop.run_in_executor(None, server.heard)
    server.say({"type": "events", "events": []}, {"type": "reply", "id": 1, "ok": True,
                                                  "result": "talker-1"})
    assert await asyncio.wait_for(call, 5) == "talker-1"
    assert await conn.receive() == {"type": "events", "events": []}  # kept, in order
    waiting = asyncio.ensure_future(conn.ask(Status()))
    await loop.run_in_executor(None, server.heard)
    conn.fail("link to robot1 lost (ssh exit status 255)")
    with pytest.raises(SessionError, match=r"^link to robot1 lost \(ssh"):
        await asyncio.wait_for(waiting, 5)
    server.hang_up()
    assert await conn.receive() is None
    conn.close()


async def test_a_dropped_link_is_reconnected_with_its_attempts_counted() -> None:
    """A Reconnector paces new connections: refused twice (the latest reason kept, each new
    reason said once, the wait doubled), then greeted by a new server."""
    relink = Reconnector(first=0.01, most=0.04)
    relink.lost("link to robot1 lost (ssh exit status 255)", "ssh exit status 255")
    assert (relink.down, relink.attempt, relink.trying_for()) == \
        ("link to robot1 lost (ssh exit status 255)", 0, None)
    said = []
    reasons = iter(["Connection refused", "Connection refused"])
    while True:
        await relink.next_attempt()
        assert relink.trying_for() is not None and relink.trying_for() >= 0  # under way
        reason = next(reasons, None)
        if reason is None:
            conn, server = await connected()  # the link is back
            break
        if relink.failed(reason):
            said.append(reason)
    assert relink.attempt == 3
    assert relink.reason == "Connection refused" and said == ["Connection refused"]
    assert relink.delay == 0.04
    relink.back()
    assert (relink.down, relink.reason, relink.attempt_since) == (None, None, None)
    conn.close()
    server.hang_up()


async def test_now_cuts_the_wait_before_the_next_attempt() -> None:
    relink = Reconnector(first=600.0)
    relink.lost("link to robot1 lost (closed)", "closed")
    began = time.monotonic()
    attempt = asyncio.ensure_future(relink.next_attempt())
    await asyncio.sleep(0)
    relink.now()
    await asyncio.wait_for(attempt, 5)
    assert relink.attempt == 1 and time.monotonic() - began < 5
