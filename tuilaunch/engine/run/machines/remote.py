"""Sessions on other machines: `[HOST:]NAME` addresses and the ssh link that carries the
session protocol.

The link is `ssh HOST <remote tuilaunch> __proxy NAME`: the proxy on the other side relays
the session's unix socket over ssh's stdin and stdout, so the same JSON lines cross it as
locally, and no port or daemon is added. ssh's end of the link is one end of a socketpair:
the client's end is then a real socket (timeouts, `makefile`, `asyncio.open_connection`),
and the blocking and asyncio clients use it exactly as they use a session's unix socket.

`TUILAUNCH_SSH_COMMAND` is the ssh command line (shell words, as git's `GIT_SSH_COMMAND`);
`TUILAUNCH_REMOTE` the tuilaunch command on the other side (a command line, run by the
remote user's shell). Our own ssh options come after the user's: ssh keeps the first value
of an option, so the user's `-o` win.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import re
import shlex
import socket
import subprocess
import threading
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ...plan.machines import Machine
from ..session.connection import Connection, NoGreeting, run_blocking
from ..session.protocol import MAX_MESSAGE, VersionMismatch
from ..session.session_dir import SessionError, check_name

PROXY_COMMAND = "__proxy"
"""The hidden subcommand of the remote tuilaunch that relays a session: `__proxy NAME`."""
LIST_COMMAND = "__ls"
"""The hidden subcommand that prints the remote sessions as `tuilaunch ls --json` does."""

SSH_OPTIONS = (
    # no prompt can work: ssh has no terminal of its own here, and a password prompt would
    # scribble over the TUI's screen or hang a script; a key (or agent) must log in
    "-o", "BatchMode=yes",
    # an unreachable machine is said in seconds, not after TCP's minutes
    "-o", "ConnectTimeout=10",
    # a dropped link (cable out, robot off) is noticed within 15 s even when idle
    "-o", "ServerAliveInterval=5", "-o", "ServerAliveCountMax=3",
    # JSON lines of log output repeat themselves: zlib takes most of the bytes off the link
    "-o", "Compression=yes",
    "-T",  # the protocol is bytes, not a terminal: no pty, no \r\n translation
)
HELLO_TIMEOUT = 30.0
"""How long the link waits for the session's greeting: an ssh login and a Python start."""

SSH_FAILED = 255  # ssh's own failure (connection, authentication), as documented in ssh(1)
NOT_FOUND = 127  # the remote shell: command not found
NOT_EXECUTABLE = 126

_HOST = re.compile(r"^[A-Za-z0-9_.%+@-]+$")


class RemoteError(SessionError):
    """A machine that cannot be reached, refuses us, or lacks tuilaunch or the session."""


@dataclass(frozen=True)
class Address:
    """Where a session is: `host` None is this machine."""

    host: str | None
    name: str

    def __str__(self) -> str:
        if self.host is None:
            return self.name
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"{host}:{self.name}"


def parse_address(text: str) -> Address:
    """`NAME`, `HOST:NAME`, `user@host:NAME` or `[IPv6]:NAME`.

    The last colon separates the host: a session name has none. A host containing colons
    (an IPv6 address) must be bracketed, as in ssh's own URIs; otherwise `fe80::1:x` could
    mean two things. A host starting with '-' is refused: ssh would read it as an option."""
    if text.startswith("["):
        close = text.find("]")
        if close < 0 or text[close + 1:close + 2] != ":":
            raise SessionError(f"session address {text!r} is not [HOST]:NAME",
                               hint="an IPv6 host is written [fe80::1]:NAME")
        host, name = text[1:close], text[close + 2:]
        if not host or not re.match(r"^[0-9A-Fa-f:.%A-Za-z]+$", host):
            raise SessionError(f"session address {text!r}: {host!r} is not a host")
        return Address(host, check_name(name))
    if ":" not in text:
        return Address(None, check_name(text))
    host, name = text.rsplit(":", 1)
    check_host(host, text)
    return Address(host, check_name(name))


def check_host(host: str, where: str | None = None) -> str:
    """A host as ssh takes it (alias, name, address, user@host); never an ssh option."""
    where = f"session address {where!r}: " if where else ""
    if not host:
        raise SessionError(f"{where}no host before ':'", hint="HOST:NAME, or NAME for here")
    if ":" in host:
        raise SessionError(f"{where}host {host!r} has a ':'",
                           hint="an IPv6 host is written in brackets: [fe80::1]:NAME")
    if host.startswith("-") or not _HOST.match(host):
        raise SessionError(f"{where}{host!r} is not a host name",
                           hint="an alias from ~/.ssh/config, a host name or user@host")
    return host


def ssh_command(environ: Mapping[str, str] | None = None) -> list[str]:
    environ = os.environ if environ is None else environ
    text = environ.get("TUILAUNCH_SSH_COMMAND") or "ssh"
    try:
        words = shlex.split(text)
    except ValueError as exc:
        raise SessionError(f"TUILAUNCH_SSH_COMMAND {text!r} cannot be read: {exc}") from None
    if not words:
        raise SessionError("TUILAUNCH_SSH_COMMAND is empty", hint="unset it to use ssh")
    return words


def remote_command(args: list[str], environ: Mapping[str, str] | None = None,
                   machine: Machine | None = None) -> str:
    """The command line the remote shell runs: the machine's `tuilaunch:` (else
    `TUILAUNCH_REMOTE`, else `tuilaunch`), then `args` quoted for that shell. ssh joins its
    remote words with spaces and hands them to the login shell, so the words are quoted
    here. A machine's `env:` is given through `env`; its `setup:` is sourced first by bash
    (ROS's setup.bash is bash, and the login shell may be another)."""
    environ = os.environ if environ is None else environ
    program = (machine.tuilaunch if machine else None) or environ.get("TUILAUNCH_REMOTE") \
        or "tuilaunch"
    words = [program, *(shlex.quote(a) for a in args)]
    if machine is not None and machine.env:
        words[:0] = ["env", *(shlex.quote(f"{k}={v}") for k, v in machine.env.items())]
    command = " ".join(words)
    if machine is not None and machine.setup:
        script = f". {shlex.quote(machine.setup)} && exec {command}"
        return f"exec bash -c {shlex.quote(script)}"
    return command


Target = str | Machine
"""A host as ssh takes it, or a machine of a machines file (its host, tuilaunch, setup
and env)."""


def _host(target: Target) -> str:
    return target.host if isinstance(target, Machine) else target


def ssh_argv(target: Target, args: list[str],
             environ: Mapping[str, str] | None = None) -> list[str]:
    """The whole ssh command running the remote tuilaunch with `args` on `target`."""
    machine = target if isinstance(target, Machine) else None
    if isinstance(target, Machine):
        # checked when the machines file was read (and may be a bare IPv6 address)
        host = target.host
        if host.startswith("-"):
            raise SessionError(f"machine {target.name}: {host!r} is not a host name")
    else:
        host = check_host(target)
    return [*ssh_command(environ), *SSH_OPTIONS, host,
            remote_command(args, environ, machine)]


def explain_failure(host: str, code: int, stderr: str, what: str,
                    environ: Mapping[str, str] | None = None,
                    machine: Machine | None = None) -> RemoteError:
    """One line for an ssh that ended before the session answered: which of ssh, the
    login, the remote tuilaunch or the session failed, from ssh's exit status and words."""
    environ = os.environ if environ is None else environ
    # a machine of a machines file is named as the file names it, and its host
    label = host if machine is None or machine.name == host else f"{machine.name} ({host})"
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    text = " ".join(lines)
    last = lines[-1] if lines else f"exit status {code}"
    ours = [i for i, line in enumerate(lines) if "tuilaunch: error: " in line]
    if ours:  # the remote tuilaunch ran and said what is wrong (and maybe a hint)
        reason = lines[ours[-1]].split("tuilaunch: error: ", 1)[1]
        after = lines[ours[-1] + 1:ours[-1] + 2]
        hint = after[0][len("hint: "):] if after and after[0].startswith("hint: ") else None
        return RemoteError(f"{label}: {reason}", hint=hint)
    if code == SSH_FAILED:
        if "Permission denied" in text:
            return RemoteError(f"{label} refused the login ({last})",
                               hint=f"`ssh {host}` must log in without a prompt: a key in "
                               "its authorized_keys, or an ssh-agent")
        if "Host key verification failed" in text or "HOST IDENTIFICATION" in text:
            return RemoteError(f"{label}: host key verification failed",
                               hint=f"ssh {host} once in a terminal to check and accept "
                               "its key")
        return RemoteError(f"cannot reach {label}: {_without_prefix(last)}")
    if machine is not None and machine.setup and machine.setup in text:
        return RemoteError(f"{label}: its setup file cannot be sourced ({last})",
                           hint="fix the machine's 'setup:' in the machines file")
    tuilaunch = (machine.tuilaunch if machine else None) or \
        environ.get("TUILAUNCH_REMOTE") or "tuilaunch"
    if code == 0 and not lines:
        # it ran and ended well, without a word of the protocol: not a tuilaunch
        variable = "the machine's 'tuilaunch:'" if machine is not None and machine.tuilaunch \
            else "TUILAUNCH_REMOTE" if environ.get("TUILAUNCH_REMOTE") else "PATH there"
        return RemoteError(f"{label}: the remote command {tuilaunch!r} exited without "
                           "speaking the session protocol (exit status 0)",
                           hint=f"is {tuilaunch} a tuilaunch? ({variable} names it)")
    if code in (NOT_FOUND, NOT_EXECUTABLE) or "command not found" in text or \
            "No such file or directory" in text:
        return RemoteError(f"{label}: tuilaunch not found there ({tuilaunch}: {last})",
                           hint="install tuilaunch there, or set TUILAUNCH_REMOTE (or the "
                           "machine's 'tuilaunch:') to its path")
    return RemoteError(f"{label}: {what} failed: {last}")


def _without_prefix(line: str) -> str:
    """`ssh: connect to host x port 22: Connection refused` without the `ssh: `."""
    return line[5:] if line.startswith("ssh: ") else line


class _StderrTail:
    """ssh's stderr, read in a thread (a chatty ssh never blocks on a full pipe); the last
    64 KiB are kept for `explain_failure`."""

    def __init__(self, process: subprocess.Popen[bytes]) -> None:
        self.process = process
        self.chunks: list[bytes] = []
        self.thread = threading.Thread(target=self._read, name="ssh-stderr", daemon=True)
        self.thread.start()

    def _read(self) -> None:
        stream = self.process.stderr
        assert stream is not None
        while chunk := os.read(stream.fileno(), 4096):
            self.chunks.append(chunk)
            while len(self.chunks) > 16:
                self.chunks.pop(0)

    def ended(self) -> tuple[int, str]:
        """ssh's exit status and what it said (it is waited for; one that lingers is
        killed)."""
        try:
            code = self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.process.kill()
            code = self.process.wait()
        self.thread.join(timeout=5)  # its last words reach the pipe before it closes
        return code, b"".join(self.chunks).decode(errors="replace")

    def failure(self, target: Target, what: str,
                environ: Mapping[str, str] | None) -> RemoteError:
        """Why ssh ended before the session answered."""
        code, text = self.ended()
        machine = target if isinstance(target, Machine) else None
        return explain_failure(_host(target), code, text, what, environ, machine)


@dataclass(eq=False, repr=False)  # a link is itself: compared and hashed by identity
class RemoteLink:
    """A running `ssh HOST tuilaunch __proxy NAME`: `sock` speaks the session protocol.

    `hello` is the session's greeting (already read). Close with `close()`: it ends ssh."""

    host: str
    name: str
    sock: socket.socket
    process: subprocess.Popen[bytes]
    hello: dict[str, Any]
    stderr: _StderrTail

    def lost_reason(self) -> str:
        """Once the link closed: one line saying why, from ssh's last words, else its exit
        status (a remote end killed outright leaves ssh nothing to say)."""
        return f"lost the link to {self.host} ({self.why_lost()})"

    def why_lost(self) -> str:
        """`lost_reason` without the host: ssh's last words or its exit status."""
        code, text = self.stderr.ended()
        lines = [line.strip() for line in text.splitlines() if line.strip()]
        return _without_prefix(lines[-1]) if lines else f"ssh exit status {code}"

    @property
    def info(self) -> dict[str, Any]:
        info: dict[str, Any] = self.hello.get("info") or {}
        return info

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self.sock.close()
        # ssh sees its stdin close and ends; a hung one is ended all the same
        try:
            self.process.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


def start_ssh(target: Target, args: list[str], environ: Mapping[str, str] | None = None,
              ) -> tuple[socket.socket, subprocess.Popen[bytes]]:
    """ssh running the remote tuilaunch with `args`, its stdin and stdout one socket of a
    pair (the other is returned); its stderr a pipe, read when it fails."""
    argv = ssh_argv(target, args, environ)
    ours, theirs = socket.socketpair()
    try:
        process = subprocess.Popen(
            argv, stdin=theirs.fileno(), stdout=theirs.fileno(), stderr=subprocess.PIPE,
            # its own session: Ctrl+C in the operator's terminal is the TUI's to handle,
            # and ssh never opens that terminal to prompt
            start_new_session=True,
            env=None if environ is None else dict(environ))
    except OSError as exc:
        ours.close()
        raise RemoteError(f"cannot run {argv[0]}: {exc.strerror or exc}",
                          hint="set TUILAUNCH_SSH_COMMAND to the ssh command") from None
    finally:
        theirs.close()
    return ours, process


def open_remote_link(target: Target, name: str, timeout: float = HELLO_TIMEOUT,
                     environ: Mapping[str, str] | None = None) -> RemoteLink:
    """Blocking: the link to session `name` on `host`, once the session greeted us, its
    socket blocking (for a blocking face: client/link.py's Link reads a copy of it).

    Raises RemoteError with one line (and a hint) saying whether the machine could not be
    reached, refused the key, has no tuilaunch, or has no such session."""
    async def opened() -> RemoteLink:
        link, conn = await open_remote_connection(target, name, timeout, environ)
        # the link keeps a copy of the socket; the connection closes its own: the session
        # says nothing more until it is asked, so nothing is left in that one's buffer
        link.sock = link.sock.dup()
        conn.close()
        await asyncio.sleep(0)  # the transport closes its socket on the loop's next turn
        return link

    link = run_blocking(opened)
    link.sock.settimeout(None)  # blocking again (the copy's mode is the same file's)
    return link


async def open_remote_connection(target: Target, name: str, timeout: float = HELLO_TIMEOUT,
                                 environ: Mapping[str, str] | None = None,
                                 ) -> tuple[RemoteLink, Connection]:
    """The link to session `name` on `host`, and the greeted Connection over it (labelled
    HOST:NAME), for the TUI's RemoteSupervisor and the placed machines' shares. RemoteError
    as `open_remote_link` says."""
    check_name(name)
    loop = asyncio.get_running_loop()
    # ssh's start forks a process: not on the loop's thread
    sock, process = await loop.run_in_executor(
        None, lambda: start_ssh(target, [PROXY_COMMAND, name], environ))
    stderr = _StderrTail(process)
    sock.setblocking(False)
    reader, writer = await asyncio.open_connection(sock=sock, limit=MAX_MESSAGE)
    conn = await _greeted(target, name, timeout, environ, reader, writer, sock, stderr)
    return RemoteLink(_host(target), name, sock, process,
                      {"type": "hello", "info": conn.info}, stderr), conn


async def _greeted(target: Target, name: str, timeout: float,
                   environ: Mapping[str, str] | None, reader: asyncio.StreamReader,
                   writer: asyncio.StreamWriter, sock: socket.socket,
                   stderr: _StderrTail) -> Connection:
    """The session's greeting over a new ssh link, checked by the Connection; what failed
    (ssh, the remote tuilaunch, the session) said in one line, ssh ended."""
    host = _host(target)
    try:
        return await Connection.greeted(reader, writer, f"{host}:{name}", timeout)
    except BaseException as exc:
        sock.close()
        loop = asyncio.get_running_loop()
        if isinstance(exc, NoGreeting) and exc.garbled is None:
            # ssh ended before a whole line: its status and words say why
            raise await loop.run_in_executor(
                None, lambda: stderr.failure(target, f"session {name}", environ)) from None
        stderr.process.kill()
        await loop.run_in_executor(None, stderr.process.wait)
        if isinstance(exc, TimeoutError):
            raise RemoteError(f"{host}: session {name} did not answer within {timeout:g} s")\
                from None
        if isinstance(exc, NoGreeting):
            raise RemoteError(f"{host}: the remote tuilaunch did not speak the session "
                              f"protocol ({exc.garbled})",
                              hint="is TUILAUNCH_REMOTE a tuilaunch?") from None
        if isinstance(exc, SessionError) and not isinstance(exc, VersionMismatch):
            raise RemoteError(f"{host}: session {name} did not greet") from None  # no hello
        raise


def run_remote(target: Target, args: list[str], timeout: float = HELLO_TIMEOUT,
               environ: Mapping[str, str] | None = None) -> str:
    """A one-shot remote tuilaunch command (e.g. `__ls`): its standard output, or a
    RemoteError saying why it failed."""
    host = _host(target)
    argv = ssh_argv(target, args, environ)
    try:
        done = subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True,
                              timeout=timeout, start_new_session=True,
                              env=None if environ is None else dict(environ))
    except subprocess.TimeoutExpired:
        raise RemoteError(f"{host}: no answer within {timeout:g} s") from None
    except OSError as exc:
        raise RemoteError(f"cannot run {argv[0]}: {exc.strerror or exc}") from None
    if done.returncode != 0:
        raise explain_failure(host, done.returncode, done.stderr.decode(errors="replace"),
                              " ".join(args), environ,
                              target if isinstance(target, Machine) else None)
    return done.stdout.decode(errors="replace")


def list_remote(target: Target, timeout: float = HELLO_TIMEOUT,
                environ: Mapping[str, str] | None = None) -> list[dict[str, Any]]:
    """The sessions on `host`, as `tuilaunch ls --json` lists them there."""
    host = _host(target)
    text = run_remote(target, [LIST_COMMAND], timeout, environ)
    try:
        sessions = json.loads(text)
    except ValueError:
        raise RemoteError(f"{host}: the remote tuilaunch did not list its sessions",
                          hint="is TUILAUNCH_REMOTE a tuilaunch?") from None
    if not isinstance(sessions, list):
        raise RemoteError(f"{host}: the remote tuilaunch did not list its sessions")
    return sessions
