"""The CLI's Link, a blocking face over one Connection, against a scripted server on a real
unix socket in this process: a request answered, replies matched by id among events, a
server that does not answer (said in one line, the link still usable after a read's
timeout or a Ctrl+C), a server that hangs up, one of another protocol version, the ssh
form on a socket already greeted, a close from another thread, a call from a coroutine."""

from __future__ import annotations

import json
import logging
import signal
import socket
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from tuilaunch.client.link import Link, LinkLost
from tuilaunch.engine.run.session import session_dir
from tuilaunch.engine.run.session.protocol import PROTOCOL_VERSION, VersionMismatch
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.engine.run.vocabulary.requests import Find, Status, Subscribe

NAME = "face"
HELLO = {"type": "hello", "info": {"protocol": PROTOCOL_VERSION, "name": NAME, "pid": 0}}


class Peer:
    """The server's end of one connection: lines written, requests read back."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.file = sock.makefile("rb")

    def say(self, *messages: dict[str, Any]) -> None:
        self.sock.sendall(b"".join(json.dumps(m).encode() + b"\n" for m in messages))

    def heard(self) -> dict[str, Any]:
        line = self.file.readline()
        assert line, "the client hung up"
        return dict(json.loads(line))

    def until_hung_up(self) -> None:
        while self.file.readline():
            pass

    def reply(self, request: dict[str, Any], result: Any) -> None:
        self.say({"type": "reply", "id": request["id"], "ok": True, "result": result})

    def hang_up(self) -> None:
        self.file.close()
        self.sock.close()


Script = Callable[[Peer], None]


class Server:
    """A session's socket (where Link looks for NAME), each connection run by `script` in
    a thread; `errors` what a script's asserts said."""

    def __init__(self, path: Path, script: Script) -> None:
        self.listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.listener.bind(str(path))
        self.listener.listen()
        self.script = script
        self.errors: list[BaseException] = []
        self.threads: list[threading.Thread] = []
        self.peers: list[Peer] = []
        self.accepting = threading.Thread(target=self._accept, daemon=True)
        self.accepting.start()

    def _accept(self) -> None:
        while True:
            try:
                sock, _ = self.listener.accept()
            except OSError:
                return  # closed: the test is over
            peer = Peer(sock)
            self.peers.append(peer)
            thread = threading.Thread(target=self._run, args=(peer,), daemon=True)
            self.threads.append(thread)
            thread.start()

    def _run(self, peer: Peer) -> None:
        try:
            self.script(peer)
        except (OSError, ValueError, AssertionError) as exc:
            self.errors.append(exc)

    def close(self) -> None:
        self.listener.shutdown(socket.SHUT_RDWR)
        self.listener.close()
        self.accepting.join(10)
        for peer in self.peers:
            peer.hang_up()
        for thread in self.threads:
            thread.join(10)
        assert not any(t.is_alive() for t in [self.accepting, *self.threads])


@pytest.fixture
def serve(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[[Script],
                                                                                 Server]]:
    runtime = tmp_path / "run"
    runtime.mkdir(mode=0o700)
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(runtime))
    servers: list[Server] = []

    def start(script: Script) -> Server:
        servers.append(Server(session_dir.socket_path(NAME), script))
        return servers[-1]

    yield start
    for server in servers:
        server.close()


def greeted_then(answer: Callable[[Peer], None]) -> Script:
    def script(peer: Peer) -> None:
        peer.say(HELLO)
        answer(peer)
    return script


def test_a_request_is_answered_and_read_as_its_reply_type(serve) -> None:
    def answer(peer: Peer) -> None:
        asked = peer.heard()
        assert (asked["op"], asked["id"]) == ("status", 1)
        peer.reply(asked, {"name": NAME, "processes": []})
        asked = peer.heard()
        assert (asked["op"], asked["id"], asked["process"]) == ("find", 2, "talker")
        peer.reply(asked, "talker-1")
        peer.until_hung_up()

    server = serve(greeted_then(answer))
    link = Link(NAME)
    try:
        assert link.info["name"] == NAME
        assert link.request(Status(resources=False), short=True).name == NAME
        assert link.request(Find(process="talker")) == "talker-1"
    finally:
        link.close()
    server.threads[0].join(10)
    assert server.errors == []  # each request as the server expected it


def test_replies_are_matched_by_id_and_the_events_between_them_kept_in_order(serve) -> None:
    """`stop` sends a request and reads its reply among the events later; a request asked
    meanwhile gets its own reply, and nothing that came before it is lost or reordered."""
    first = {"type": "events", "events": [{"kind": "exited", "process": "a-1"}]}
    second = {"type": "events", "events": [{"kind": "exited", "process": "b-2"}]}

    def answer(peer: Peer) -> None:
        sent, asked = peer.heard(), peer.heard()
        assert (sent["id"], asked["id"]) == (1, 2)
        peer.say(first, {"type": "reply", "id": 1, "ok": True, "result": {"stopped": True}},
                 second)
        peer.reply(asked, "talker-1")
        peer.say({"type": "ended"})
        peer.hang_up()

    serve(greeted_then(answer))
    link = Link(NAME, timeout=10)
    try:
        sending = link.send(Subscribe())
        assert link.request(Find(process="talker")) == "talker-1"
        assert list(link.pending) == [first, {"type": "reply", "id": sending, "ok": True,
                                              "result": {"stopped": True}}, second]
        assert link.receive() == first
        assert link.receive_until(time.monotonic() + 10)["id"] == sending
        assert list(link.messages()) == [second, {"type": "ended"}]  # then the close
        assert link.ended and link.lost() is None
        assert link.receive() is None
    finally:
        link.close()


def test_a_server_that_says_nothing_is_said_in_one_line_within_the_answer_timeout(
        serve) -> None:
    serve(lambda peer: peer.heard())  # accepts, never greets
    began = time.monotonic()
    with pytest.raises(SessionError, match=rf"^session {NAME} did not answer within 0.5 s"):
        Link(NAME, answer_timeout=0.5)
    assert time.monotonic() - began < 5


def test_a_read_that_times_out_leaves_the_link_usable(serve) -> None:
    """`hz --duration`: the stream read until a deadline, then a short request answered;
    a short request the server leaves unanswered is the one line of a silent server."""
    said = threading.Event()

    def answer(peer: Peer) -> None:
        peer.reply(peer.heard(), "talker-1")  # after the client's deadline passed
        said.wait(10)
        peer.heard()  # asked, never answered

    serve(greeted_then(answer))
    link = Link(NAME, timeout=None, answer_timeout=0.5)
    try:
        began = time.monotonic()
        with pytest.raises(TimeoutError):
            link.receive_until(began + 0.3)
        assert 0.25 < time.monotonic() - began < 5
        assert link.request(Find(process="talker"), short=True) == "talker-1"
        said.set()
        with pytest.raises(SessionError, match=rf"^session {NAME} did not answer within 0.5 s"):
            link.request(Status(), short=True)
    finally:
        link.close()


def test_ctrl_c_reaches_the_command_at_once_and_the_link_still_answers(
        serve, caplog: pytest.LogCaptureFixture) -> None:
    """Ctrl+C on `hz`: the interrupt stops the wait (no stray task logged), and the figures
    are asked for after it on the same link."""
    main = threading.get_ident()

    def answer(peer: Peer) -> None:
        peer.heard()
        signal.pthread_kill(main, signal.SIGINT)  # the user's Ctrl+C while it waits
        peer.reply(peer.heard(), "talker-1")
        peer.heard()

    serve(greeted_then(answer))
    link = Link(NAME, timeout=None)
    try:
        with caplog.at_level(logging.DEBUG, logger="asyncio"):
            began = time.monotonic()
            with pytest.raises(KeyboardInterrupt):
                link.request(Status())
            assert time.monotonic() - began < 5
            assert link.request(Find(process="talker"), short=True) == "talker-1"
    finally:
        link.close()
    assert [r.message for r in caplog.records if r.levelno >= logging.WARNING] == []


def test_a_server_that_hangs_up_during_a_request_is_said_with_the_request(serve) -> None:
    serve(greeted_then(lambda peer: (peer.heard(), peer.hang_up())))
    link = Link(NAME)
    try:
        with pytest.raises(SessionError,
                           match=rf"^session {NAME} closed the connection during status$"):
            link.request(Status())
        assert link.receive() is None and list(link.messages()) == []
        assert link.lost() is None  # here, no link is between: the session is what closed
    finally:
        link.close()


def test_no_server_is_one_line_with_a_hint(serve) -> None:
    with pytest.raises(SessionError, match=rf"^session {NAME} does not answer \(") as caught:
        Link(NAME)
    assert caught.value.hint == "tuilaunch ls lists the running sessions"


def test_a_server_of_another_version_is_one_line_naming_both(serve) -> None:
    old = {"type": "hello", "info": {"protocol": 1, "tuilaunch": "0.1.0"}}
    serve(lambda peer: (peer.say(old), peer.heard()))
    with pytest.raises(VersionMismatch) as caught:
        Link(NAME)
    said = str(caught.value)
    assert "\n" not in said
    assert said.startswith(f"session {NAME} speaks protocol 1 (tuilaunch 0.1.0), this "
                           f"tuilaunch speaks {PROTOCOL_VERSION}")


def test_the_ssh_form_reads_a_socket_already_greeted_and_says_a_lost_link() -> None:
    """`Link.connected`: the hello already read (remote.open_remote_link); errors name
    HOST:NAME; `release` leaves the socket open for the TUI; a link that closes before the
    session ended is LinkLost with ssh's last words, and `close` ends the ssh."""
    ours, theirs = socket.socketpair()
    peer = Peer(theirs)
    closed: list[bool] = []
    link = Link.connected(NAME, ours, HELLO, "robot1", on_close=lambda: closed.append(True),
                          why_lost=lambda: "ssh exit status 255")
    try:
        asking = threading.Thread(target=lambda: peer.say(
            {"type": "reply", "id": peer.heard()["id"], "ok": False, "error": "no process x"}))
        asking.start()
        with pytest.raises(SessionError, match=rf"^session robot1:{NAME}: no process x$"):
            link.request(Find(process="x"))
        asking.join(10)
        link.release()
        peer.say({"type": "events", "events": []})  # the socket given still carries the link
        assert ours.recv(100).startswith(b'{"type": "events"')
        assert closed == []
    finally:
        link.close()
    assert closed == [True]
    ours.close()
    theirs.settimeout(5)
    assert theirs.recv(1) == b""  # no copy of the socket left open: ssh would wait on it
    peer.hang_up()

    ours, theirs = socket.socketpair()
    link = Link.connected(NAME, ours, HELLO, "robot1", on_close=ours.close,
                          why_lost=lambda: "ssh exit status 255")
    try:
        theirs.close()
        with pytest.raises(LinkLost, match=r"^link to robot1 lost: ssh exit status 255$"):
            list(link.messages())
    finally:
        link.close()
    assert ours.fileno() == -1


def test_a_close_from_another_thread_ends_a_read_under_way(serve) -> None:
    """plot --csv reads each session in a thread and closes the links from the main one
    on Ctrl+C: the read under way ends as a closed connection, not an error."""
    serve(greeted_then(lambda peer: peer.heard()))
    link = Link(NAME, timeout=None)
    got: list[Any] = []
    reading = threading.Thread(target=lambda: got.append(link.receive()))
    reading.start()
    deadline = time.monotonic() + 10
    while not link._loop.is_running():  # the reader waits in its loop
        assert time.monotonic() < deadline
        time.sleep(0.01)
    link.close()
    reading.join(10)
    assert not reading.is_alive() and got == [None]
    assert link.receive() is None  # and any later read, at once


async def test_a_coroutine_may_call_it_as_it_called_a_blocking_socket(serve) -> None:
    """A test or a tool in a coroutine asks with it: the call blocks, as it always did."""
    serve(greeted_then(lambda peer: (peer.reply(peer.heard(), "talker-1"), peer.heard())))
    link = Link(NAME)
    try:
        assert link.request(Find(process="talker")) == "talker-1"
    finally:
        link.close()
