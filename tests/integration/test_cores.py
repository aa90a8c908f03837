"""A crash names its signal and, when the system kept a core, where it is."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tuilaunch.engine.run.process.cores import core_location, describe_death, signal_name

from .terminal_harness import PROGRAMS

SEGV = str(PROGRAMS / "segv.py")


def crash(tmp_path: Path, core_limit: str) -> tuple[int, int]:
    """segv.py run in tmp_path with the given `ulimit -c`: (pid, return code)."""
    proc = subprocess.Popen(["sh", "-c", f'ulimit -c {core_limit} && exec "$0" "$1"',
                             sys.executable, SEGV], cwd=tmp_path, stdout=subprocess.PIPE)
    out = proc.communicate(timeout=60)[0]
    assert b"about to crash" in out
    return proc.pid, proc.returncode


def test_signal_names() -> None:
    assert describe_death(-signal.SIGSEGV) == "killed by SIGSEGV"
    assert describe_death(-signal.SIGABRT) == "killed by SIGABRT"
    assert describe_death(3) == "exit code 3"
    assert signal_name(77) == "signal 77"


def test_a_real_segfault_points_at_its_core_when_the_system_keeps_one(tmp_path: Path) -> None:
    if resource.getrlimit(resource.RLIMIT_CORE)[1] == 0:
        pytest.skip("the hard RLIMIT_CORE is 0 here: no process may dump core")
    started = time.time()
    pid, code = crash(tmp_path, "unlimited")
    assert code == -signal.SIGSEGV
    where = core_location(pid, signal.SIGSEGV, str(tmp_path), comm="python3", since=started,
                          core_limit=resource.RLIM_INFINITY)
    pattern = Path("/proc/sys/kernel/core_pattern").read_text().strip()
    if pattern.startswith("|"):
        assert where is not None and ("coredumpctl" in where or "piped to" in where)
    elif where is None:
        pytest.skip(f"the kernel wrote no core for core_pattern {pattern!r} "
                    f"(container or file system refuses it)")
    else:
        assert Path(where).is_file() and Path(where).stat().st_size > 0
        assert Path(where).parent == tmp_path or os.path.isabs(pattern)


def test_no_core_no_word_when_rlimit_core_is_zero(tmp_path: Path) -> None:
    started = time.time()
    pid, code = crash(tmp_path, "0")
    assert code == -signal.SIGSEGV
    assert core_location(pid, signal.SIGSEGV, str(tmp_path), since=started,
                         core_limit=0) is None
    assert core_location(pid, signal.SIGSEGV, str(tmp_path), core_limit=0,
                         pattern="|/usr/lib/systemd/systemd-coredump %P %u %g %s %t") is None


def test_patterns_as_the_kernel_expands_them(tmp_path: Path) -> None:
    coredump = "|/usr/lib/systemd/systemd-coredump %P %u %g %s %t 9223372036854775808 %h"
    assert core_location(42, signal.SIGSEGV, core_limit=1 << 20, pattern=coredump) == \
        "kept by systemd-coredump: coredumpctl info 42"
    apport = "|/usr/share/apport/apport -p%p -s%s -c%c -d%d -P%P -u%u -g%g -- %E"
    assert "piped to apport" in str(core_location(42, signal.SIGABRT, core_limit=-1,
                                                  pattern=apport))
    (tmp_path / "core.talker.42.1700000000").write_bytes(b"\x7fELF")
    assert core_location(42, signal.SIGSEGV, str(tmp_path), comm="talker",
                         pattern="core.%e.%p.%t") == str(tmp_path / "core.talker.42.1700000000")
    assert core_location(43, signal.SIGSEGV, str(tmp_path), pattern="core.%e.%p.%t") is None
    (tmp_path / "core.42").write_bytes(b"\x7fELF")  # core_uses_pid=1 appends .PID
    assert core_location(42, signal.SIGSEGV, str(tmp_path), pattern="core",
                         uses_pid=True) == str(tmp_path / "core.42")
    # an old core of the same name is not this crash's
    assert core_location(42, signal.SIGSEGV, str(tmp_path), pattern="core", uses_pid=True,
                         since=time.time() + 60) is None
    # a signal that dumps no core (SIGKILL, SIGTERM) has none to point at
    assert core_location(42, signal.SIGKILL, str(tmp_path), pattern="core",
                         uses_pid=True) is None


def test_a_crash_is_a_signal_nobody_asked_for() -> None:
    from tuilaunch.engine.run.process.cores import is_crash
    assert is_crash(-signal.SIGSEGV, requested=False)
    assert not is_crash(-signal.SIGINT, requested=True)  # our own stop
    assert not is_crash(1, requested=False)  # an exit code the program chose
    assert not is_crash(0, requested=False)


def test_a_crash_described_with_its_core(tmp_path: Path) -> None:
    from tuilaunch.engine.run.process.cores import describe_crash
    if resource.getrlimit(resource.RLIMIT_CORE)[1] == 0:
        pytest.skip("the hard RLIMIT_CORE is 0 here: no process may dump core")
    pattern = Path("/proc/sys/kernel/core_pattern").read_text().strip()
    if pattern.startswith("|"):
        pytest.skip(f"cores are piped here ({pattern!r}): no file to name")
    started = time.time()
    pid, code = crash(tmp_path, "unlimited")
    text = describe_crash(pid, code, str(tmp_path), since=started, comm="python3")
    if "core" not in text:
        pytest.skip(f"the kernel wrote no core for core_pattern {pattern!r}")
    assert text.startswith("killed by SIGSEGV (core dumped: " + str(tmp_path))
    assert describe_crash(pid, 3) == "exit code 3"
