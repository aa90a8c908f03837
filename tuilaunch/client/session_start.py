"""Starting a session: its name reserved, its server started in a session of its own (no
terminal), and waited for until it answers. The command line (`tuilaunch FILE`, `--detach`,
`serve FILE`) and the TUI's first start go through here, so a TUI is always a client of a
session server, as a user runs it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from ..engine.run.session import session_dir
from ..engine.run.session.owner_gate import OWNER_ENV
from ..engine.run.session.session_dir import SessionError

_RESERVED: dict[str, int] = {}
"""Names this command picked, and the descriptor of each one's lock, until the server it
starts takes the lock over."""


def session_name_for(path: str, name: str | None) -> str:
    """The name a new session of `path` takes, reserved until its server holds it: `name`
    as given, else the file's stem and the first free number (two launches started in the
    same second take two names); a name a live or starting session holds is refused."""
    if name:
        lock = session_dir.reserve(session_dir.check_name(name))
        if lock is None or session_dir.is_alive(name):
            if lock is not None:
                os.close(lock)
            raise SessionError(f"a session named {name} is already running",
                               hint="choose another --name, or tuilaunch attach " + name)
    else:
        name, lock = session_dir.new_name(session_dir.launch_stem(path))
    _RESERVED[name] = lock
    return name


def start_session(path: str, arguments: dict[str, str], name: str | None, log_dir: Path,
                  positional: list[str] | None = None,
                  timeout: float = 60.0, placement: dict[str, Any] | None = None,
                  ) -> tuple[str, subprocess.Popen[bytes]]:
    """Starts a session server in its own session (no terminal) and waits until it answers.
    `positional` is FILE or PACKAGE FILE as given: what the launch file sees in sys.argv;
    `placement` (`--machines`) is {"text", "path", "share"} as engine/server_main.py reads
    it."""
    starting = spawn_session(path, arguments, name, log_dir, positional, placement)
    return starting.name, starting.wait(timeout)


def spawn_session(path: str, arguments: dict[str, str], name: str | None, log_dir: Path,
                  positional: list[str] | None = None,
                  placement: dict[str, Any] | None = None, owner: bool = False,
                  ) -> StartingServer:
    """A session server started, not waited for: `tuilaunch FILE` starts it before it
    imports the TUI, so the server loads the file while the TUI imports. `owner`: the
    launch's processes wait for the owner's `PlanShown` (session/owner_gate.py)."""
    if name is None or name not in _RESERVED:
        name = session_name_for(path, name)
    lock = _RESERVED.pop(name)
    try:
        log_dir.mkdir(parents=True, exist_ok=True)
        server_log = log_dir / "session.log"
        env = {**os.environ, session_dir.LOCK_FD_ENV: str(lock)}
        if owner:
            env[OWNER_ENV] = "1"
        with open(server_log, "ab") as errors:
            server = subprocess.Popen(
                [sys.executable, "-P", "-m", "tuilaunch.engine.server_main", name,
                 os.path.abspath(path), str(log_dir), json.dumps(arguments),
                 json.dumps(positional or [path]),
                 *([json.dumps(placement)] if placement else [])],
                stdin=subprocess.DEVNULL, stdout=errors, stderr=errors,
                start_new_session=True, pass_fds=(lock,), env=env)
    finally:
        os.close(lock)  # the server holds the name now (or it failed and lets it go)
    return StartingServer(name, server, server_log)


class StartingServer:
    """A session's server started, until it answers (`wait`); called, it waits with the
    default timeout (the TUI's `start_server`)."""

    def __init__(self, name: str, process: subprocess.Popen[bytes], log: Path) -> None:
        self.name = name
        self.process = process
        self.log = log
        self.own_error: str | None = None
        """The server's own error (the file did not load, a bad argument), once it ended
        with one: said as the command line says it, without the session's name."""

    def __call__(self) -> subprocess.Popen[bytes]:
        return self.wait()

    def wait(self, timeout: float = 60.0) -> subprocess.Popen[bytes]:
        """The server, once it answers (it has loaded the file and resolved the plan);
        SessionError: it ended first (its own one-line error) or did not answer in time."""
        name, server = self.name, self.process
        deadline = time.monotonic() + timeout
        # ours, not another server that took the name at the same instant
        while (session_dir.read_info(name) or {}).get("pid") != server.pid or \
                not session_dir.is_alive(name):
            if server.poll() is not None:
                text = self.log.read_text(errors="replace").strip()
                if "tuilaunch: error: " in text:  # the server's own one-line error and hint
                    self.own_error = text.rsplit("tuilaunch: error: ", 1)[-1]
                    raise SessionError(self.own_error)
                reason = (text.splitlines() or ["no message"])[-1]  # else its last words
                raise SessionError(f"session {name} did not start: {reason}")
            if time.monotonic() > deadline:
                server.kill()
                raise SessionError(f"session {name} did not answer within {timeout:g} s")
            time.sleep(0.02)
        return server


REMOTE_START_TIMEOUT = 90.0
"""Seconds `--on HOST` waits for the session there to answer (ssh, then the launch's own
start, which `--detach` there waits for up to 60 s)."""


def start_remote_session(host: str, items: list[str], name: str | None) -> str:
    """`tuilaunch --on HOST FILE [name:=value ...]`: FILE (or PACKAGE FILE) started on HOST
    as a detached session, by the tuilaunch there (`tuilaunch ITEMS --detach` over ssh: the
    file, its packages and its environment are HOST's); the session's name. A RemoteError
    (SessionError) names what failed: HOST not reached, or the remote tuilaunch's own line
    (no such file, a name taken)."""
    from ..engine.run.machines.remote import check_host, run_remote

    args = [*items, "--detach", *(["--name", name] if name else [])]
    out = run_remote(check_host(host), args, timeout=REMOTE_START_TIMEOUT)
    started = out.strip().splitlines()[-1:] if out.strip() else []
    if not started:
        raise SessionError(f"{host}: the remote tuilaunch started no session",
                           hint="is TUILAUNCH_REMOTE a tuilaunch?")
    return started[0].strip()
