"""After a crash: the signal's name, and where the system kept the core, if it kept one.

Linux decides from /proc/sys/kernel/core_pattern (man 5 core): a pattern starting with `|`
pipes the core to a program (systemd-coredump, apport), anything else is a file path,
relative to the dead process's working directory, with %-specifiers. With RLIMIT_CORE 0
(the usual default) no file is written, and systemd-coredump keeps nothing either, so
nothing is said then: a hint at a core that does not exist would send the operator looking.
"""

from __future__ import annotations

import glob
import os
import resource
import signal
import socket
from pathlib import Path

CORE_PATTERN = "/proc/sys/kernel/core_pattern"
CORE_USES_PID = "/proc/sys/kernel/core_uses_pid"

DUMPS_CORE = frozenset({signal.SIGQUIT, signal.SIGILL, signal.SIGTRAP, signal.SIGABRT,
                        signal.SIGBUS, signal.SIGFPE, signal.SIGSEGV, signal.SIGXCPU,
                        signal.SIGXFSZ, signal.SIGSYS})
"""Signals whose default action dumps core (man 7 signal, action "Core")."""


def signal_name(number: int) -> str:
    """`SIGSEGV` for 11; `signal 77` for a number without a name."""
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"


def describe_death(code: int) -> str:
    """A return code as an operator reads it: `killed by SIGSEGV` (Popen's -11), `exit code 1`."""
    return f"killed by {signal_name(-code)}" if code < 0 else f"exit code {code}"


def _read(path: str) -> str | None:
    try:
        return Path(path).read_text().strip()
    except OSError:
        return None


def _expand(pattern: str, pid: int, number: int, comm: str | None) -> str:
    """The pattern as a glob: the specifiers known after the death are filled in, the others
    (time, thread id, executable path...) match anything."""
    known = {"p": str(pid), "P": str(pid), "s": str(number), "u": str(os.getuid()),
             "g": str(os.getgid()), "h": socket.gethostname(), "%": "%"}
    if comm is not None:
        known["e"] = comm[:15]  # the kernel's comm: 15 characters at most
    out = []
    i = 0
    while i < len(pattern):
        char = pattern[i]
        if char == "%" and i + 1 < len(pattern):
            spec = pattern[i + 1]
            out.append(glob.escape(known[spec]) if spec in known else "*")
            i += 2
        else:
            out.append(glob.escape(char))
            i += 1
    return "".join(out)


def core_location(pid: int, number: int, cwd: str | None = None, *, comm: str | None = None,
                  since: float | None = None, core_limit: int | None = None,
                  pattern: str | None = None, uses_pid: bool | None = None) -> str | None:
    """Where the core of process `pid`, killed by signal `number`, went: a file path, or how
    to reach a core a program kept (`coredumpctl`); None when there is none to point at.

    `cwd` is the process's working directory (tuilaunch's when None); `comm` its executable
    name as the kernel knew it; `core_limit` its RLIMIT_CORE (tuilaunch's, which children
    inherit, when None); `since` its start (time.time()), so that a core an earlier crash left
    under the same name is not taken for this one. `pattern` and `uses_pid` default to the
    kernel's settings.
    """
    if number not in DUMPS_CORE:
        return None
    pattern = _read(CORE_PATTERN) if pattern is None else pattern
    if not pattern:
        return None
    limit = resource.getrlimit(resource.RLIMIT_CORE)[0] if core_limit is None else core_limit
    if pattern.startswith("|"):
        if limit == 0:
            return None
        program = os.path.basename(pattern[1:].split()[0]) if pattern[1:].split() else ""
        if program == "systemd-coredump":
            return f"kept by systemd-coredump: coredumpctl info {pid}"
        return f"piped to {program or 'a program'} (core_pattern {pattern!r})"
    if uses_pid is None:
        uses_pid = _read(CORE_USES_PID) == "1"
    if uses_pid and "%p" not in pattern:
        pattern += ".%p"
    base = Path(cwd) if cwd is not None else Path.cwd()
    cores = []
    for name in glob.glob(_expand(pattern, pid, number, comm), root_dir=base):
        try:
            modified = (base / name).stat().st_mtime
        except OSError:
            continue
        if since is None or modified >= since - 1:  # 1 s: file systems' coarse clocks
            cores.append((modified, base / name))
    if not cores:
        return None  # not written: RLIMIT_CORE, an unwritable directory, a setuid program
    return str(max(cores)[1])


def is_crash(code: int, requested: bool) -> bool:
    """A death by a signal nobody asked for (no stop, no shutdown): `failed`, not `exited`.

    A signal sent by tuilaunch's own stop is not one; neither is an exit code, which the
    program chose (ros2 launch's "process has died" covers both; the state tells them apart).
    """
    return code < 0 and not requested


def describe_crash(pid: int, code: int, cwd: str | None = None, *, since: float | None = None,
                   comm: str | None = None) -> str:
    """`killed by SIGSEGV (core dumped: /home/r2/core.1234)`, or without the parenthesis
    when no core was kept: one line for the node's state, the tree and `status --json`."""
    text = describe_death(code)
    if code < 0:
        where = core_location(pid, -code, cwd, since=since, comm=comm)
        if where is not None:
            label = "core dumped" if where.startswith("/") else "core"
            text += f" ({label}: {where})"
    return text
