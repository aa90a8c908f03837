"""The remote end of an ssh link: relays a session's unix socket over stdin and stdout.

`tuilaunch __proxy NAME` (hidden from --help) runs
on the machine of the session, started by `ssh HOST ...`; its stdin and stdout are ssh's
channel. It relays bytes both ways, in chunks as they come, until the session closes or
the client goes (ssh's channel closes): it never parses the protocol, so it adds nothing
but a copy. The session server checks the peer's uid as for any local client, and ssh has
already authenticated the user.

`tuilaunch __ls` prints the machine's sessions as `tuilaunch ls --json` does.
"""

from __future__ import annotations

import errno
import json
import os
import selectors
import socket
import sys
import time
from pathlib import Path
from typing import Any

from ...errors import LaunchError
from ..session import session_dir
from ..session.connection import Connection, run_blocking
from ..session.protocol import ProtocolError
from ..session.session_dir import SessionError
from ..vocabulary.requests import Status, StatusReply

CHUNK = 1 << 16
LS_ANSWER_TIMEOUT = 3.0  # as `tuilaunch ls`: a stopped server costs this, once
USAGE = "usage: tuilaunch __proxy NAME | tuilaunch __ls"
SERVER_GONE = 3
"""The proxy's status when the session closed the link without ending (its server was
killed): its last line says so, which the client reads as the session's end, not a lost
link (client/link.py, client/remote_supervisor.py)."""
SERVER_GONE_WORDS = "ended without a word"
ENDED = b'{"type":"ended"'
"""The session's last message when it ends as it should (protocol.py's encoding)."""
TAIL = 64


def connect(name: str) -> socket.socket:
    """The session's socket, connected; SessionError when there is no such session."""
    session_dir.check_name(name)
    if name not in session_dir.live_sessions():
        alive = session_dir.live_sessions(clean=False)
        raise SessionError(f"no running session named {name}",
                           hint=f"running: {', '.join(alive)}" if alive else "no session runs "
                           "there")
    sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        sock.connect(str(session_dir.socket_path(name)))
    except OSError as exc:
        sock.close()
        raise SessionError(f"session {name} does not answer ({exc.strerror or exc})")\
            from None
    return sock


def relay(sock: socket.socket, stdin: int, stdout: int) -> bytes | None:
    """Copies stdin -> sock and sock -> stdout until the session closes (then the last
    bytes it sent: did it say it ended?), or stdout fails or the client hung up first
    (None: the session closing then is its answer to that, no death to explain).

    Blocking writes on purpose: when ssh's side stops reading, the proxy stops reading the
    session, and the server's bounded per-client queue takes over (it drops output for this
    client only), exactly as for a slow local client. On stdin's end (the client closed
    its sending side) the socket's sending side is shut, and the session's answers still
    come back until it closes."""
    selector = selectors.DefaultSelector()
    tail = b""
    hung_up = False  # the client closed its sending side
    selector.register(stdin, selectors.EVENT_READ, "in")
    selector.register(sock, selectors.EVENT_READ, "out")
    try:
        while selector.get_map():
            for key, _ in selector.select():
                if key.data == "in":
                    data = _read(stdin)
                    if not data:
                        hung_up = True
                        selector.unregister(stdin)
                        try:
                            sock.shutdown(socket.SHUT_WR)
                        except OSError:
                            return tail
                        continue
                    try:
                        sock.sendall(data)
                    except OSError:
                        return tail  # the session is gone
                else:
                    try:
                        data = sock.recv(CHUNK)
                    except OSError:
                        data = b""
                    if not data:
                        return None if hung_up else tail
                    _write_all(stdout, data)
                    tail = (tail + data)[-TAIL:]
    except BrokenPipeError:
        return None  # ssh's channel closed: the client is gone
    finally:
        selector.close()
    return None


def _gone(pid: int, wait: float = 2.0) -> bool:
    """Whether the session's server is dead (or dying: a zombie), within `wait` seconds:
    a server that ends as asked closes its sockets a moment before it exits."""
    deadline = time.monotonic() + wait
    while True:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            state = "" if session_dir.pid_alive(pid) else "gone"
        if state in ("gone", "Z", "X"):
            return True
        if time.monotonic() >= deadline:
            return False
        time.sleep(0.05)


def _read(fd: int) -> bytes:
    try:
        return os.read(fd, CHUNK)
    except OSError as exc:
        if exc.errno in (errno.EIO, errno.ECONNRESET, errno.EPIPE):
            return b""
        raise


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


# --- listing ---------------------------------------------------------------------------------
# The same JSON as `tuilaunch ls --json` (cli/commands.cmd_ls prints these rows); it lives in
# the engine because the remote side's `__ls` must not need the command line.

LS_KEYS = ("name", "file", "arguments", "pid", "started", "log_dir", "counts", "answering")


def session_status(name: str, timeout: float = LS_ANSWER_TIMEOUT) -> StatusReply:
    """A session's `status` reply, asked over its socket (a Connection: another version's
    greeting is refused, as its status may differ); blocking."""
    async def ask() -> StatusReply:
        conn = await Connection.open_unix(str(session_dir.socket_path(name)), name, timeout)
        try:
            return await conn.call(Status(resources=False), timeout)  # a listing
        finally:
            conn.close()

    try:
        return run_blocking(ask)
    except TimeoutError:
        raise SessionError(f"session {name} did not answer within {timeout:g} s") from None
    except (ConnectionError, ProtocolError) as exc:
        raise SessionError(f"session {name}: {exc}") from None


def list_sessions() -> list[dict[str, Any]]:
    """`tuilaunch ls --json`'s rows: answering sessions with their counts; a stopped or
    stuck one from the info it wrote at its start; one that ended meanwhile not at all."""
    rows = []
    for name in session_dir.live_sessions():
        try:
            rows.append({**session_status(name).listing(), "answering": True})
        except SessionError:
            info = session_dir.read_info(name)
            if info is None or not session_dir.pid_alive(int(info.get("pid") or 0)):
                continue
            rows.append({"name": name, "file": info.get("file", "?"),
                         "arguments": info.get("arguments", {}), "pid": info.get("pid"),
                         "started": info.get("started", 0.0), "log_dir": info.get("log_dir", ""),
                         "counts": {}, "answering": False})
    return [{key: row[key] for key in LS_KEYS} for row in rows]


# --- entry -----------------------------------------------------------------------------------

def main(argv: list[str]) -> int:
    """`__proxy NAME` or `__ls`; errors are one line on stderr and exit status 2."""
    try:
        if argv[:1] == ["__ls"] and len(argv) == 1:
            print(json.dumps(list_sessions(), indent=2))
            return 0
        if argv[:1] == ["__proxy"] and len(argv) == 2:
            sock = connect(argv[1])
            pid = int((session_dir.read_info(argv[1]) or {}).get("pid") or 0)
            try:
                tail = relay(sock, sys.stdin.fileno(), sys.stdout.fileno())
            finally:
                sock.close()
            if tail is not None and ENDED not in tail and pid and _gone(pid):
                # the server died (kill -9, a crash): its last words, for the client, which
                # would otherwise take the closed link for a network's fault
                print(f"tuilaunch: error: session {argv[1]} {SERVER_GONE_WORDS}: its "
                      f"server (pid {pid}) is gone", file=sys.stderr)
                return SERVER_GONE
            return 0
    except LaunchError as exc:
        print(f"tuilaunch: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    print(USAGE, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
