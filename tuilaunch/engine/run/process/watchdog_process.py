"""The watchdog process (see watchdog.py): holds the read end of the launcher's pipe and, when
it ends, stops every process of the launch.

It runs as a script (`python -I -S watchdog_process.py TOKEN GRACE`) beside every launch,
and starts while the launch's first processes start, on the same cores: it imports nothing
beyond os, sys and time. `_signal` is the `signal` module without its enums, whose import
(enum, functools) took longer than the rest of the watchdog's start.
"""

import _signal
import os
import sys
import time

MARK = "TUILAUNCH_LAUNCH_ID"
"""Environment variable every process of a launch inherits: the launch tokens, `:`-joined
(a launch started by a launch carries both)."""


def _launch_processes(token: str, groups: set[int]) -> list[int]:
    """Live processes in one of the groups or carrying the token in their environment."""
    found: list[int] = []
    me = os.getpid()
    needle = f"{MARK}=".encode()
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == me:
            continue
        try:
            with open(f"/proc/{entry}/stat", "rb") as handle:
                fields = handle.read().rsplit(b")", 1)[1].split()
            if fields[0] == b"Z":
                continue
            if int(fields[2]) in groups:
                found.append(int(entry))
                continue
            with open(f"/proc/{entry}/environ", "rb") as handle:
                environ = handle.read()
        except (OSError, IndexError, ValueError):
            continue  # gone meanwhile, or not ours to read
        for item in environ.split(b"\0"):
            if item.startswith(needle) and token.encode() in item[len(needle):].split(b":"):
                found.append(int(entry))
                break
    return found


def sweep(token: str, groups: set[int], grace: float) -> None:
    for sig, wait in ((_signal.SIGTERM, grace), (_signal.SIGKILL, 2.0)):
        targets = _launch_processes(token, groups)
        if not targets:
            return
        for pid in targets:
            try:
                os.kill(pid, sig)
            except OSError:
                pass
        deadline = time.monotonic() + wait
        while time.monotonic() < deadline:
            time.sleep(0.02)
            remaining = _launch_processes(token, groups)
            if not remaining:
                return
            for pid in remaining:  # late forks of a dying process get the same signal
                if pid not in targets:
                    targets.append(pid)
                    try:
                        os.kill(pid, sig)
                    except OSError:
                        pass


def main(argv: list[str]) -> None:
    token, grace = argv[1], float(argv[2])
    for sig in (_signal.SIGINT, _signal.SIGTERM, _signal.SIGHUP, _signal.SIGPIPE):
        _signal.signal(sig, _signal.SIG_IGN)  # a terminal's Ctrl+C or hang-up is not for us
    groups: set[int] = set()
    pending = b""
    while True:
        try:
            chunk = os.read(0, 4096)
        except InterruptedError:
            continue
        except OSError:
            break
        if not chunk:
            break
        *lines, pending = (pending + chunk).split(b"\n")
        for line in lines:
            if line[:1] == b"+":
                groups.add(int(line[1:]))
            elif line[:1] == b"-":
                groups.discard(int(line[1:]))
    sweep(token, groups, grace)


if __name__ == "__main__":
    main(sys.argv)
