"""CPU, memory and threads per process tree from /proc, and the memory-growth flag."""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator

import pytest

from tuilaunch.engine.run.session.resources import ResourceSampler, Usage, growing, tree_pids

BURN = "while True: pass"
GROW = textwrap.dedent("""
    import time
    hoard = []
    print('ready', flush=True)
    while True:
        if len(hoard) < 400:
            hoard.append(bytearray(1 << 20))  # 1 MiB, touched: resident
        time.sleep(0.05)
""")
THREADS = textwrap.dedent("""
    import threading, time
    for _ in range(4):
        threading.Thread(target=time.sleep, args=(3600,), daemon=True).start()
    print('ready', flush=True)
    time.sleep(3600)
""")
IDLE = "import time; print('ready', flush=True); time.sleep(3600)"


@pytest.fixture
def spawn() -> Iterator:
    procs: list[subprocess.Popen[str]] = []

    def start(*cmd: str, ready: bool = True) -> subprocess.Popen[str]:
        proc = subprocess.Popen(list(cmd), stdout=subprocess.PIPE, text=True,
                                start_new_session=True)
        procs.append(proc)
        if ready:
            assert proc.stdout is not None and proc.stdout.readline().strip() == "ready"
        return proc

    yield start
    for proc in procs:
        with contextlib.suppress(ProcessLookupError):  # a test may have killed it already
            os.killpg(proc.pid, 9)  # the whole group: children of a shell too
        proc.wait(timeout=30)
        if proc.stdout is not None:
            proc.stdout.close()


def sample_until(sampler: ResourceSampler, roots: dict[str, int], condition,
                 timeout: float = 60) -> dict[str, Usage]:
    """Samples every 0.2 s until `condition(result)` holds (deadline: a busy machine)."""
    deadline = time.monotonic() + timeout
    result: dict[str, Usage] = {}
    while time.monotonic() < deadline:
        result = sampler.sample(roots)
        if condition(result):
            return result
        time.sleep(0.2)
    raise AssertionError(f"condition not met within {timeout} s: {result}")


def test_cpu_of_a_tree_counts_its_children(spawn):
    # a shell whose child burns a core: the launched process is the shell
    shell = spawn("/bin/sh", "-c", f"{sys.executable} -c '{BURN}' & echo ready; wait")
    idle = spawn(sys.executable, "-c", IDLE)
    roots = {"burner": shell.pid, "idle": idle.pid}
    sampler = ResourceSampler()
    first = sampler.sample(roots)
    assert first["burner"].cpu_percent is None  # no interval yet
    found = sample_until(sampler, roots, lambda r: len(tree_pids(shell.pid)) == 2 and (
        r["burner"].cpu_percent or 0) > 30)
    assert found["burner"].processes == 2
    assert found["idle"].cpu_percent is not None and found["idle"].cpu_percent < 30
    # the tree's memory is the shell's plus its child's: more than the child's own, read in
    # the same sample (against another process, a few pages either way would decide it)
    (child,) = set(tree_pids(shell.pid)) - {shell.pid}
    both = sampler.sample({"burner": shell.pid, "child": child})
    assert both["child"].processes == 1
    assert both["burner"].rss_bytes > both["child"].rss_bytes > 1_000_000


def test_threads_and_a_gone_process(spawn):
    proc = spawn(sys.executable, "-c", THREADS)
    sampler = ResourceSampler()
    usage = sampler.sample({"t": proc.pid})["t"]
    assert usage.threads >= 5
    assert usage.as_dict()["threads"] == usage.threads
    os.killpg(proc.pid, 9)
    proc.wait(timeout=30)
    assert sampler.sample({"t": proc.pid}) == {}


def test_a_process_whose_memory_keeps_growing_is_flagged(spawn):
    grower = spawn(sys.executable, "-c", GROW)
    idle = spawn(sys.executable, "-c", IDLE)
    roots = {"grower": grower.pid, "idle": idle.pid}
    sampler = ResourceSampler(growth_samples=5, growth_seconds=0.8, growth_percent=10)
    found = sample_until(sampler, roots, lambda r: r["grower"].memory_growing)
    assert not found["idle"].memory_growing


def test_growth_rule():
    rising = [(t, 100 + 10 * t) for t in range(10)]
    assert growing(rising, samples=5, seconds=4, percent=10)
    assert not growing(rising, samples=5, seconds=5, percent=10)  # too short a span
    assert not growing(rising, samples=5, seconds=4, percent=50)  # too small a rise
    wobble = [*rising[:8], (8, 150), (9, 200)]
    assert not growing(wobble, samples=5, seconds=4, percent=10)  # it fell once
    assert not growing([(0, 100), (1, 100)], samples=5, seconds=0, percent=0)
