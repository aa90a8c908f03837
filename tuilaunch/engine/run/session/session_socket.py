"""Where clients find a session: its `<name>.lock`, its socket (0600) and its info file.

The lock names the session while its server lives; the socket is bound anew whenever it
goes missing (logind removes $XDG_RUNTIME_DIR at the last logout, a tmp cleaner or an `rm`
removes a socket), so a launch never runs on with no way to attach, stop or even list it.
"""

from __future__ import annotations

import asyncio
import os
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from ...errors import LaunchError
from . import session_dir
from .protocol import MAX_MESSAGE

REACHABLE_CHECK = 1.0
"""Seconds between checks that the session's socket is still where clients look."""

ClientCallback = Callable[[asyncio.StreamReader, asyncio.StreamWriter], Awaitable[None]]


class SessionSocket:
    """The session `name`'s files: `claim()` then `bind()`, `stay_reachable()` as a task,
    `close()` at the end. `info()` is written next to the socket on every bind;
    `log(text, level)` says what went wrong."""

    def __init__(self, name: str, on_client: ClientCallback,
                 info: Callable[[], dict[str, Any]],
                 log: Callable[[str, str], None]) -> None:
        self.name = name
        self.on_client = on_client
        self.info = info
        self.log = log
        self._server: asyncio.AbstractServer | None = None
        self._bound: tuple[int, int] | None = None  # the socket file we listen on
        self._bound_path: Path | None = None
        self._lock = -1  # the descriptor holding `<name>.lock`

    def claim(self) -> None:
        """Takes the name (held until this process ends); refuses a name in use."""
        self._lock = session_dir.claim(self.name)
        if session_dir.is_alive(self.name):
            os.close(self._lock)
            raise session_dir.SessionError(f"a session named {self.name} is already running",
                                           hint="choose another --name")

    async def bind(self) -> None:
        """Listens on the session's socket path (anew: the old socket, if any, is closed)."""
        if self._server is not None:
            self._server.close()
            self._server = None
        path = session_dir.socket_path(self.name)
        old = self._bound_path
        if old is not None and old.parent != path.parent and identity_or_none(old) == self._bound:
            # the folder moved ($XDG_RUNTIME_DIR came back): no stale files left behind
            for suffix in (".sock", ".json", ".lock"):
                old.with_suffix(suffix).unlink(missing_ok=True)
        path.unlink(missing_ok=True)
        old_umask = os.umask(0o177)  # the socket is created 0600, never briefly wider
        try:
            self._server = await asyncio.start_unix_server(self.on_client, path=str(path),
                                                           limit=MAX_MESSAGE)
        finally:
            os.umask(old_umask)
        os.chmod(path, 0o600)
        self._bound = identity(path)
        self._bound_path = path
        session_dir.write_info(self.name, self.info())

    def owns_name(self) -> bool:
        """Whether `<name>.lock` is still the one this server holds."""
        try:
            lock_path = session_dir.session_root() / f"{self.name}.lock"
            return identity(lock_path) == identity_fd(self._lock)
        except (OSError, LaunchError):
            return False

    def close(self) -> None:
        """Stops listening and removes the session's files (never a later session's)."""
        if self._server is not None:
            self._server.close()
        if self.owns_name():  # never the files of a later session given our name
            session_dir.remove(self.name)

    async def stay_reachable(self) -> None:
        """Puts the session's files back when someone removed them: logind removes
        $XDG_RUNTIME_DIR when the user's last login ends (the ssh logout after --detach),
        a tmp cleaner or an `rm` removes a socket. Without this, the launch would run on
        with no way to attach, stop or even list it. One stat a second is the whole cost."""
        warned = False
        while True:
            await asyncio.sleep(REACHABLE_CHECK)
            try:
                if not self.owns_name():
                    try:
                        lock = session_dir.claim(self.name)
                    except session_dir.SessionError:
                        continue  # a newer session took the name; it keeps it
                    os.close(self._lock)
                    self._lock = lock
                if identity_or_none(
                        session_dir.socket_path(self.name)) != self._bound:
                    await self.bind()
                    self.log(f"session {self.name}: its socket was removed; "
                             f"listening again at {session_dir.socket_path(self.name)}", "WARN")
                warned = False
            except (OSError, LaunchError) as exc:
                if not warned:  # e.g. the folder cannot be made; try again, say it once
                    self.log(f"session {self.name}: cannot put its socket back: {exc}", "ERROR")
                    warned = True


def identity(path: Path) -> tuple[int, int]:
    info = os.stat(path)
    return info.st_dev, info.st_ino


def identity_or_none(path: Path) -> tuple[int, int] | None:
    try:
        return identity(path)
    except FileNotFoundError:
        return None


def identity_fd(fd: int) -> tuple[int, int]:
    info = os.fstat(fd)
    return info.st_dev, info.st_ino
