"""Time from `tuilaunch FILE` to the whole tree on screen, beside `tuilaunch FILE --print`,
for a launch file whose `generate_launch_description` takes 1 s (a big xacro's stand-in),
and how many times each loads the file (its module level appends a line to a file).

The TUI runs on a real pseudo-terminal; the tree is whole once its last process's name is
on screen. `--before DIR` runs another checkout (e.g. `git worktree add /tmp/wt-before
main`) in the same run, turn about with this one, so both see the same machine.

    python bench/tree_bench.py [--runs 3] [--before DIR]
"""

from __future__ import annotations

import argparse
import os
import pty
import select
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

LEAVES = 5
SLOW_FILE = f"""
import os, time
from launch import LaunchDescription
from launch.actions import ExecuteProcess

with open(os.environ["TREE_BENCH_LOADS"], "a") as loads:  # once per load of this file
    loads.write("load\\n")


def generate_launch_description():
    time.sleep(1.0)
    return LaunchDescription([ExecuteProcess(cmd=["sleep", "600"], name=f"leaf_{{i}}")
                              for i in range(1, {LEAVES + 1})])
"""
LAST = f"leaf_{LEAVES}".encode()


def environment(checkout: Path, folder: Path, loads: Path) -> dict[str, str]:
    """`checkout` first on the path (the commands run in `folder`: `python -m` puts the
    working directory first, which would pick the checkout the bench is run from)."""
    return {**os.environ, "PYTHONPATH": str(checkout), "TERM": "xterm-256color",
            "ROS_LOG_DIR": str(folder / "log"), "XDG_RUNTIME_DIR": str(folder),
            "TREE_BENCH_LOADS": str(loads)}


def count(loads: Path) -> int:
    try:
        return len(loads.read_text().splitlines())
    finally:
        loads.unlink(missing_ok=True)


def printed(checkout: Path, path: Path, folder: Path) -> tuple[float, int]:
    loads = folder / "loads"
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "tuilaunch", str(path), "--print"], check=True,
                   cwd=folder, capture_output=True, env=environment(checkout, folder, loads))
    return time.perf_counter() - start, count(loads)


def tree_on_screen(checkout: Path, path: Path, folder: Path) -> tuple[float, int]:
    """Seconds until the last process's name is drawn, and the loads of the whole launch
    (counted once the TUI has quit and its server ended)."""
    loads = folder / "loads"
    master, slave = pty.openpty()
    start = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path)], stdin=slave,
                            stdout=slave, stderr=slave, env=environment(checkout, folder, loads),
                            start_new_session=True, cwd=folder)
    os.close(slave)
    seen = b""
    try:
        while LAST not in seen:
            if time.perf_counter() - start > 60:
                raise AssertionError(f"the tree never showed: {seen[-400:]!r}")
            if select.select([master], [], [], 0.02)[0]:
                seen += os.read(master, 1 << 16)
        elapsed = time.perf_counter() - start
        # until every process runs: the launch is whole, then q stops it
        while seen.count(b"running") == 0:
            if time.perf_counter() - start > 60:
                raise AssertionError("the launch never ran")
            if select.select([master], [], [], 0.05)[0]:
                seen += os.read(master, 1 << 16)
        deadline = time.monotonic() + 60
        keys = b"qy"  # q, then y in its "Stop them all and quit?"
        while proc.poll() is None and time.monotonic() < deadline:
            os.write(master, keys[:1])
            keys = keys[::-1]
            if select.select([master], [], [], 0.5)[0]:
                try:
                    os.read(master, 1 << 16)
                except OSError:
                    break
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        os.close(master)
    wait_servers_gone(folder)
    return elapsed, count(loads)


def wait_servers_gone(folder: Path) -> None:
    """The session's server stops its processes after the TUI has left; loads are counted
    once it is gone (a relaunch would add one)."""
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        ps = subprocess.run(["pgrep", "-f", f"server_main .* {folder}"], capture_output=True,
                            text=True)
        if not ps.stdout.strip():
            return
        time.sleep(0.1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--before", type=Path, help="another checkout, run turn about")
    options = parser.parse_args()
    here = Path(__file__).resolve().parent.parent
    checkouts = {"this": here, **({"before": options.before.resolve()}
                                  if options.before else {})}
    figures: dict[tuple[str, str], list[tuple[float, int]]] = {}
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        path = folder / "slow.launch.py"
        path.write_text(SLOW_FILE)
        for _ in range(options.runs):
            for label, checkout in checkouts.items():
                for how, measure in (("--print", printed), ("TUI", tree_on_screen)):
                    figures.setdefault((label, how), []).append(
                        measure(checkout, path, folder))
    print(f"load 1-min {os.getloadavg()[0]:.1f}; {options.runs} runs each, turn about")
    print(f"{'checkout':10} {'command':8} {'median s':>9} {'runs s':24} loads")
    for (label, how), runs in figures.items():
        seconds = [s for s, _ in runs]
        print(f"{label:10} {how:8} {statistics.median(seconds):9.2f} "
              f"{', '.join(f'{s:.2f}' for s in seconds):24} "
              f"{sorted({n for _, n in runs})}")


if __name__ == "__main__":
    main()
