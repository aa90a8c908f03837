"""Supervisor figures, one run on this machine, each beside its floor.

1. Time from command to all N processes started (N = 10, 100) against a bare Python script
   starting the same N with a `subprocess.Popen` loop (best of 3 each, side by side), and
   tuilaunch's thread count with N children (constant: no thread per child).
2. Lines per second absorbed and logged from 4 processes printing as fast as they can,
   against the same 4 processes writing straight to files, with the count of lines lost.
3. tuilaunch's own CPU while 100 quiet processes run (target: under 1% of a core).

    python bench/run_bench.py
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FLOOD_LINES = 1_000_000
TRIES = 3


def write_launch(folder: Path, name: str, body: str) -> Path:
    path = folder / name
    path.write_text("from launch import LaunchDescription\n"
                    "from launch.actions import ExecuteProcess\n"
                    f"def generate_launch_description():\n    return LaunchDescription({body})\n")
    return path


def tuilaunch(path: Path, log_dir: Path, out: int | None = subprocess.PIPE) -> subprocess.Popen:
    env = {**os.environ, "ROS_LOG_DIR": str(log_dir)}
    return subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                            stdout=out, stderr=subprocess.DEVNULL, text=True, env=env,
                            start_new_session=True)


def stop(proc: subprocess.Popen) -> None:
    os.killpg(proc.pid, signal.SIGINT)
    proc.wait(timeout=120)


def wait_started(proc: subprocess.Popen, count: int) -> None:
    started = 0
    assert proc.stdout is not None
    while started < count:
        line = proc.stdout.readline()
        if not line:
            raise RuntimeError("tuilaunch ended before every process started")
        started += "process started" in line


def threads_of(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Threads:"):
            return int(line.split()[1])
    return 0


def spawn_once(folder: Path, count: int) -> tuple[float, int]:
    path = write_launch(folder, f"spawn{count}.py",
                        f"[ExecuteProcess(cmd=['sleep', '600'], name=f's{{i}}') "
                        f"for i in range({count})]")
    start = time.perf_counter()
    proc = tuilaunch(path, folder / f"log{count}")
    wait_started(proc, count)
    elapsed = time.perf_counter() - start
    threads = threads_of(proc.pid)
    stop(proc)
    return elapsed, threads


def floor_once(count: int) -> float:
    floor_script = ("import subprocess, sys\n"
                    f"ps = [subprocess.Popen(['sleep', '600']) for _ in range({count})]\n"
                    "print('all', flush=True)\n"
                    "sys.stdin.readline()\n"
                    "[p.kill() for p in ps]\n"
                    "[p.wait() for p in ps]\n")
    start = time.perf_counter()
    floor = subprocess.Popen([sys.executable, "-c", floor_script], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True)
    assert floor.stdout is not None and floor.stdin is not None
    floor.stdout.readline()
    elapsed = time.perf_counter() - start
    floor.stdin.write("\n")
    floor.stdin.close()
    floor.wait()
    return elapsed


def spawn_time(folder: Path, count: int) -> tuple[float, float, int]:
    ours: list[float] = []
    floors: list[float] = []
    threads = 0
    for _ in range(TRIES):  # interleaved, so both see the same machine
        elapsed, threads = spawn_once(folder, count)
        ours.append(elapsed)
        floors.append(floor_once(count))
    return min(ours), min(floors), threads


def flood(folder: Path, tty: bool) -> tuple[float, float, int]:
    """4 x `seq`: through tuilaunch (pseudo-terminals, or pipes), against the same 4 writing
    straight to files the way they write on that channel: line by line on a terminal
    (`stdbuf -oL`), in 4 KB blocks on a pipe."""
    emulate = "None" if tty else "False"
    name = "tty" if tty else "pipe"
    path = write_launch(folder, f"flood_{name}.py",
                        f"[ExecuteProcess(cmd=['seq', '1', '{FLOOD_LINES}'], name=f'f{{i}}', "
                        f"emulate_tty={emulate}) for i in range(4)]")
    log_dir = folder / f"flood_log_{name}"
    start = time.perf_counter()
    proc = tuilaunch(path, log_dir, out=subprocess.DEVNULL)
    proc.wait(timeout=600)
    ours = 4 * FLOOD_LINES / (time.perf_counter() - start)
    logged = sum(sum(1 for _ in open(f, "rb")) for f in log_dir.glob("*/f*.log"))
    buffering = "stdbuf -oL " if tty else ""
    start = time.perf_counter()
    direct = [subprocess.Popen(f"{buffering}seq 1 {FLOOD_LINES} > {folder}/direct{i}.txt",
                               shell=True) for i in range(4)]
    for writer in direct:
        writer.wait()
    floor = 4 * FLOOD_LINES / (time.perf_counter() - start)
    return ours, floor, 4 * FLOOD_LINES - logged


def idle_cpu(folder: Path, seconds: float = 10.0) -> float:
    path = write_launch(folder, "quiet.py",
                        "[ExecuteProcess(cmd=['sleep', '600'], name=f'q{i}') for i in range(100)]")
    proc = tuilaunch(path, folder / "quiet_log")
    wait_started(proc, 100)
    time.sleep(1.0)

    def cpu() -> float:
        fields = Path(f"/proc/{proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    before = cpu()
    time.sleep(seconds)
    used = cpu() - before
    stop(proc)
    return 100 * used / seconds


def main() -> None:
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        for count in (10, 100):
            ours, floor, threads = spawn_time(folder, count)
            print(f"start {count:>3} processes: tuilaunch {ours:.3f} s (command to all "
                  f"started, best of {TRIES}), bare Python Popen loop {floor:.3f} s, "
                  f"ratio {ours / floor:.2f}x; tuilaunch threads with {count} children: "
                  f"{threads}")
        for tty, channel, floor_how in ((True, "pseudo-terminals (the default)", "line by line"),
                                        (False, "pipes (emulate_tty=False)", "in blocks")):
            ours_rate, direct_rate, lost = flood(folder, tty)
            print(f"4 x {FLOOD_LINES:,} lines through {channel}: tuilaunch absorbed and logged "
                  f"{ours_rate:,.0f} lines/s (command to end), the same processes writing "
                  f"straight to files {floor_how} {direct_rate:,.0f} lines/s (ratio "
                  f"{direct_rate / ours_rate:.2f}x), lines lost: {lost}")
        print(f"CPU of tuilaunch with 100 quiet processes: {idle_cpu(folder):.2f}% of a core "
              "(target < 1%)")


if __name__ == "__main__":
    main()
