"""Creating one child: its output channels (pipes or pseudo-terminals), then the process.

Either everything exists afterwards, or nothing does: a failure (no file descriptors left,
no such executable, a bad working directory) closes what was opened and raises OSError, so
no child runs untracked.

Its own session (`setsid`) makes the child the leader of a process group the supervisor
signals as one. Without a terminal for stdin it is started with vfork + exec (fast, and safe
from threads). With one, the terminal must become the session's controlling terminal (so
ctrl+c typed is SIGINT to its foreground group, and job control works, as gdb needs), and
only the child itself can ask for that (TIOCSCTTY, after setsid): subprocess offers no other
way than `preexec_fn`, which costs a fork instead of a vfork. What it runs is a few calls
into C with no import, lock or allocation of note, so the child cannot deadlock on a lock
another thread held at the fork.

A forked child keeps tuilaunch's signal handlers until exec, and until setsid it is in
tuilaunch's process group: a ctrl+c in tuilaunch's terminal then would run tuilaunch's
handler in the child, which writes to the event loop's wake-up fd it shares, and tuilaunch
would see a second ctrl+c (and escalate its stop at once). So signals stay blocked across
the fork; in the child, once in its own session, what arrived meanwhile is discarded (the
supervisor's stop signals the new group itself) before its mask is restored for exec.
"""

from __future__ import annotations

import fcntl
import functools
import os
import shutil
import signal
import struct
import subprocess
import termios
from dataclasses import dataclass
from typing import Any


@dataclass
class Channel:
    """The launcher's end of one output stream of a child."""

    name: str  # "stdout" | "stderr"
    fd: int
    tty: bool
    stdin: bool = False
    """The child reads this terminal as its stdin too: what is written to `fd` is typed."""
    controlling: bool = False
    """It is the child's controlling terminal too: the kernel turns a typed ctrl+c into
    SIGINT. Otherwise the writer does (run/terminal_input.py)."""


@dataclass
class Child:
    popen: subprocess.Popen[bytes]
    channels: list[Channel]

    @property
    def terminal(self) -> Channel | None:
        """The channel whose fd is the child's keyboard (stdin), if it has one."""
        return next((c for c in self.channels if c.stdin), None)


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


_CATCHABLE = frozenset(signal.valid_signals()) - {signal.SIGKILL, signal.SIGSTOP}


def _take_terminal(mask: Any, ioctl: Any = fcntl.ioctl, request: int = termios.TIOCSCTTY,
                   sigmask: Any = signal.pthread_sigmask, drain: Any = signal.sigtimedwait,
                   catchable: Any = _CATCHABLE, restore: int = signal.SIG_SETMASK) -> None:
    """Runs in the child between fork and exec: stdin becomes its controlling terminal.

    Defaults bind what it calls, so nothing is looked up or imported in the child; a
    failure leaves a terminal that still reads and writes, only without signals.
    """
    try:
        ioctl(0, request, 0)
    except OSError:
        pass
    while drain(catchable, 0) is not None:
        pass  # sent to tuilaunch's group before setsid: not for this child's program
    sigmask(restore, mask)


def _popen_with_terminal(cmd: list[str], **options: Any) -> subprocess.Popen[bytes]:
    """Popen whose child takes its stdin as controlling terminal (see the module's doc)."""
    saved = signal.pthread_sigmask(signal.SIG_BLOCK, _CATCHABLE)
    try:
        return subprocess.Popen(cmd, preexec_fn=functools.partial(_take_terminal, saved),
                                **options)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, saved)


def spawn(cmd: list[str], env: dict[str, str], cwd: str | None, tty: bool, *,
          terminal_stdin: bool = True, controlling_terminal: bool = False) -> Child:
    """Starts `cmd` with each output stream on its own channel.

    With `tty`, stdout and stderr are two pseudo-terminals, as launch's emulate_tty does:
    programs line-buffer and colour as in a terminal, and stderr stays apart from stdout.
    With `terminal_stdin` too, stdout's terminal is also the child's stdin and controlling
    terminal, as in a terminal window: keyboard nodes (teleop_twist_keyboard, a debugger)
    read what is typed into it (`Child.terminal`), and what is typed is echoed into stdout.

    By default the terminal is not the child's controlling terminal, so the child starts
    with a vfork instead of a fork (a fork of a 250 MB tuilaunch costs ~8 ms more per
    start, measured here); the writer of its keys then turns a typed ctrl+c into SIGINT as
    the kernel would (run/terminal_input.py). `controlling_terminal=True` (a run under gdb,
    which needs job control) makes it the controlling terminal: as in a terminal window,
    when the child (the session's leader) exits, what it left running in its foreground
    group gets SIGHUP (a daemon that setsid's or ignores SIGHUP stays).

    Otherwise stdin is /dev/null. ros2 launch gives every child launch's own stdin; here
    that is the operator's keyboard in the TUI (a node would steal keys from it) or nothing
    in a session server, so a child without its own terminal reads nothing.
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
        keyboard = tty and terminal_stdin
        if keyboard:
            channels[0].stdin = True
            channels[0].controlling = controlling_terminal
        if keyboard and not controlling_terminal:
            popen = subprocess.Popen(cmd, stdin=theirs[0], stdout=theirs[0],
                                     stderr=theirs[1], env=env, cwd=cwd,
                                     start_new_session=True)
        elif keyboard:
            popen = _popen_with_terminal(cmd, stdin=theirs[0], stdout=theirs[0],
                                         stderr=theirs[1], env=env, cwd=cwd,
                                         start_new_session=True)
        else:
            popen = subprocess.Popen(cmd, stdin=_stdin(), stdout=theirs[0],
                                     stderr=theirs[1], env=env, cwd=cwd,
                                     start_new_session=True)
    except BaseException:
        for fd in ours:
            os.close(fd)
        raise
    finally:
        for fd in theirs:
            os.close(fd)
    return Child(popen, channels)
