"""Creating one child: its output channels (pipes or pseudo-terminals), then the process.

Either everything exists afterwards, or nothing does: a failure (no file descriptors left,
no such executable, a bad working directory) closes what was opened and raises OSError, so
no child runs untracked.

No `preexec_fn`: the child is started with vfork + exec (fast, and safe from threads); its
own session (`setsid`) makes it the leader of a process group the supervisor signals as one.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import struct
import subprocess
import termios
from dataclasses import dataclass


@dataclass
class Channel:
    """The launcher's end of one output stream of a child."""

    name: str  # "stdout" | "stderr"
    fd: int
    tty: bool


@dataclass
class Child:
    popen: subprocess.Popen[bytes]
    channels: list[Channel]


_size: bytes | None = None


def _window_size() -> bytes:
    """tuilaunch's own terminal size (or 160x48), read once: what `ls` or a progress bar sees."""
    global _size
    if _size is None:
        columns, rows = shutil.get_terminal_size((160, 48))
        _size = struct.pack("HHHH", rows, columns, 0, 0)
    return _size


def _open_pty() -> tuple[int, int]:
    """A pseudo-terminal that passes bytes through unchanged (no `\\n` -> `\\r\\n`)."""
    master, slave = os.openpty()
    try:
        attrs = termios.tcgetattr(slave)
        attrs[1] &= ~termios.OPOST
        termios.tcsetattr(slave, termios.TCSANOW, attrs)
        fcntl.ioctl(slave, termios.TIOCSWINSZ, _window_size())
    except OSError:
        os.close(master)
        os.close(slave)
        raise
    return master, slave


def _channel(name: str, tty: bool) -> tuple[Channel, int]:
    read_end, write_end = _open_pty() if tty else os.pipe()
    os.set_blocking(read_end, False)
    return Channel(name, read_end, tty), write_end


_devnull: int | None = None


def _stdin() -> int:
    """One /dev/null for every child's stdin, opened once (an open per child costs time)."""
    global _devnull
    if _devnull is None:
        _devnull = os.open(os.devnull, os.O_RDONLY | os.O_CLOEXEC)
    return _devnull


def spawn(cmd: list[str], env: dict[str, str], cwd: str | None, tty: bool) -> Child:
    """Starts `cmd` with stdin from /dev/null and each output stream on its own channel.

    With `tty`, stdout and stderr are two pseudo-terminals, as launch's emulate_tty does:
    programs line-buffer and colour as in a terminal, and stderr stays apart from stdout.
    """
    ours: list[int] = []
    theirs: list[int] = []
    channels: list[Channel] = []
    try:
        for name in ("stdout", "stderr"):
            channel, child_end = _channel(name, tty)
            ours.append(channel.fd)
            theirs.append(child_end)
            channels.append(channel)
        popen = subprocess.Popen(cmd, stdin=_stdin(), stdout=theirs[0],
                                 stderr=theirs[1], env=env, cwd=cwd, start_new_session=True)
    except BaseException:
        for fd in ours:
            os.close(fd)
        raise
    finally:
        for fd in theirs:
            os.close(fd)
    return Child(popen, channels)
