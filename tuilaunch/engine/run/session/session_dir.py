"""Where sessions live: a private folder of `<name>.sock` sockets and `<name>.json` infos.

The folder is `$XDG_RUNTIME_DIR/tuilaunch` (per user, on tmpfs, gone at logout), else
`~/.ros/tuilaunch` (`$ROS_HOME/tuilaunch`); it is made 0700 and must belong to the user,
so no other user can reach a socket even before the server checks the peer's uid.
"""

from __future__ import annotations

import errno
import fcntl
import json
import os
import re
import socket
import stat
from pathlib import Path
from typing import Any

from ...errors import LaunchError

_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")


class SessionError(LaunchError):
    """A session cannot be found, named or reached."""


def session_root() -> Path:
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    if runtime and os.path.isdir(runtime) and os.access(runtime, os.W_OK | os.X_OK):
        root = Path(runtime) / "tuilaunch"
    else:
        home = os.environ.get("ROS_HOME") or os.path.expanduser("~/.ros")
        root = Path(home) / "tuilaunch"
    root.mkdir(mode=0o700, parents=True, exist_ok=True)
    info = root.stat()
    if info.st_uid != os.getuid():
        raise SessionError(f"session folder {root} belongs to another user",
                           hint="set XDG_RUNTIME_DIR to a folder of your own")
    if stat.S_IMODE(info.st_mode) != 0o700:
        os.chmod(root, 0o700)
    return root


def check_name(name: str) -> str:
    if not _NAME.match(name):
        raise SessionError(f"session name {name!r} is not usable",
                           hint="use letters, digits, '_', '.' and '-' (at most 64)")
    return name


def socket_path(name: str) -> Path:
    return session_root() / f"{check_name(name)}.sock"


def info_path(name: str) -> Path:
    return session_root() / f"{check_name(name)}.json"


def is_alive(name: str) -> bool:
    """A session is alive when its socket accepts a connection."""
    path = session_root() / f"{name}.sock"
    probe = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    probe.settimeout(2.0)
    try:
        probe.connect(str(path))
    except TimeoutError:
        return True  # a server that is stopped, with its backlog full: there, not answering
    except OSError as exc:
        if exc.errno in (errno.ECONNREFUSED, errno.ENOENT, errno.ENOTSOCK):
            return False
        raise SessionError(f"session {name}: cannot reach {path}: {exc.strerror}") from None
    finally:
        probe.close()
    return True


LOCK_FD_ENV = "TUILAUNCH_SESSION_LOCK_FD"
"""The descriptor of `<name>.lock` its starter reserved and handed to the server."""


def claim(name: str) -> int:
    """Holds `<name>.lock` for the server's lifetime (the returned descriptor): of two
    servers started with one name at the same instant, the second is refused, instead of
    taking over the first one's socket path. A lock its starter reserved (`reserve`) and
    handed over is taken as it is."""
    handed = _handed_over(name)
    if handed is not None:
        return handed
    fd = reserve(name)
    if fd is None:
        raise SessionError(f"a session named {name} is already running",
                           hint="choose another --name")
    return fd


def reserve(name: str) -> int | None:
    """`<name>.lock` locked (its descriptor), or None when another holds it. The command
    line reserves the name it picks, and hands the lock to the server it starts: two
    launches started in the same second pick two names (a name is seen taken from the
    moment it is picked, not once its server is up)."""
    path = session_root() / f"{check_name(name)}.lock"
    fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o600)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        return None
    return fd


def _handed_over(name: str) -> int | None:
    """The lock the starter reserved for this name, if it handed one over (its children
    must not inherit it: the variable goes, the descriptor is closed on exec)."""
    value = os.environ.pop(LOCK_FD_ENV, None)
    if not value:
        return None
    try:
        fd = int(value)
        held = os.fstat(fd)
        path = os.stat(session_root() / f"{check_name(name)}.lock")
    except (ValueError, OSError):
        return None
    if (held.st_dev, held.st_ino) != (path.st_dev, path.st_ino):
        return None  # not this name's lock: the usual claim decides
    os.set_inheritable(fd, False)
    return fd


def remove(name: str) -> None:
    root = session_root()
    for suffix in (".sock", ".json", ".lock"):
        (root / f"{name}{suffix}").unlink(missing_ok=True)


def read_info(name: str) -> dict[str, Any] | None:
    try:
        data = json.loads((session_root() / f"{name}.json").read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def write_info(name: str, info: dict[str, Any]) -> None:
    path = info_path(name)
    temporary = path.with_suffix(".json.tmp")
    temporary.write_text(json.dumps(info))
    os.chmod(temporary, 0o600)
    temporary.replace(path)  # a reader never sees half a file


def live_sessions(clean: bool = True) -> list[str]:
    """Names of the sessions whose server answers, oldest first; with `clean`, the sockets
    and infos of dead ones (a server that was SIGKILLed) are removed."""
    root = session_root()
    names = {p.stem for suffix in ("sock", "json", "lock") for p in root.glob(f"*.{suffix}")}
    alive = []
    for name in names:
        if not _NAME.match(name):
            continue
        if is_alive(name):
            alive.append(name)
        elif clean:
            # removed while its lock is held here: a check that nobody holds it, then the
            # removal, let a starter take the name in between and lose its lock file to
            # the removal (then two starters held one name, seen under load)
            fd = reserve(name)
            if fd is not None:  # nobody holds it: a dead server's files
                try:
                    remove(name)
                finally:
                    os.close(fd)
    return sorted(alive, key=lambda n: (read_info(n) or {}).get("started", 0.0))


def new_name(stem: str) -> tuple[str, int]:
    """`stem-N` with the smallest N not taken by a live session, reserved (`reserve`): the
    name and its lock's descriptor."""
    base = re.sub(r"[^A-Za-z0-9_.-]", "_", stem)[:56] or "launch"
    if not base[0].isalnum():
        base = "l" + base
    taken = set(live_sessions())
    number = 1
    while True:
        name = f"{base}-{number}"
        if name not in taken:
            fd = reserve(name)
            if fd is not None:
                if not is_alive(name):
                    return name, fd
                os.close(fd)
        number += 1


def launch_stem(path: str) -> str:
    """`bringup` for bringup.py, bringup.launch.py, bringup.launch.xml."""
    name = os.path.basename(path)
    for suffix in (".launch.py", ".launch.xml", ".launch.yaml", ".launch.yml", ".py", ".xml",
                   ".yaml", ".yml"):
        if name.endswith(suffix) and len(name) > len(suffix):
            return name[: -len(suffix)]
    return name


def pid_alive(pid: int) -> bool:
    """Whether a process (a session server) lives; a zombie counts as gone: our own
    unreaped child, or an orphan that PID 1 reaps late (a container's init may take a
    second, or never)."""
    if pid <= 0:
        return False  # 0 and -1 would ask about a whole process group
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:  # our own child (the foreground case) is a zombie until reaped
        if os.waitpid(pid, os.WNOHANG) != (0, 0):
            return False
    except ChildProcessError:
        pass
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] \
            not in ("Z", "X")
    except (OSError, IndexError):
        return True  # no /proc: what kill said
