"""Supervisor figures, one run on this machine, each beside its floor.

1. Time from command to all N processes started (N = 10, 100) against a bare Python script
   starting the same N with a `subprocess.Popen` loop (best of TRIES each, interleaved), and
   tuilaunch's thread count with N children (constant: no thread per child). Target at 100:
   at most 2x the floor.
2. A flood: 4 processes each printing FLOOD_LINES lines as fast as they can, through
   pipes (the default, as in launch), all of it logged with 0 lines lost, against the
   floor of the same 4 writers writing the same way straight to files. The target row's
   writers write each line unbuffered, as it is made (awk with fflush(): one write(2) a
   line, as a ROS node's logger writes to stderr); `seq` writes 4 KB blocks to a pipe as
   to a file. Two ratios: the flood itself (first writer started to last line logged,
   from tuilaunch's own stamps in launch.log and the log files; target at most 1.5x) and
   command to end (tuilaunch's own start-up included, which the start figure measures).
   Then the same through pseudo-terminals (emulate_tty=True; against the writers
   line-buffered to files, `stdbuf -oL`, as a terminal makes stdout; `seq` writes 8 KB
   blocks anyway), beside a minimal reader of the same terminals (read, write to a file):
   what the terminals cost under any launcher.
3. tuilaunch's own CPU while 100 quiet processes run (target: under 1% of a core).

ros2 launch is not installed on this machine (no ROS apt packages; `launch` is not on PyPI
for this interpreter), so its column is absent: the floors stand in for it.

tuilaunch runs as an installed copy would: with its bytecode cached (a run with
PYTHONDONTWRITEBYTECODE compiles every module at each start, which no installed package
does), so the first, warming run is not counted.

    python bench/run_bench.py
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

FLOOD_LINES = 500_000
TRIES = 5


def write_launch(folder: Path, name: str, body: str) -> Path:
    path = folder / name
    path.write_text("from launch import LaunchDescription\n"
                    "from launch.actions import ExecuteProcess\n"
                    f"def generate_launch_description():\n    return LaunchDescription({body})\n")
    return path


def tuilaunch(path: Path, log_dir: Path, out: int | None = subprocess.PIPE) -> subprocess.Popen:
    env = {**os.environ, "ROS_LOG_DIR": str(log_dir)}
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # as installed: bytecode cached
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


def flood_window(log_dir: Path) -> float:
    """Seconds from the first writer started (launch.log) to the last line logged (each log
    line starts with the time tuilaunch read it)."""
    starts = [float(line.split()[0]) for path in log_dir.glob("*/launch.log")
              for line in path.read_text().splitlines() if line.split()[1:2] == ["started"]]
    last = 0.0
    for path in log_dir.glob("*/f*.log"):
        with open(path, "rb") as handle:
            handle.seek(max(0, os.path.getsize(path) - 4096))
            tail = handle.read().splitlines()
        last = max(last, float(tail[-1].split()[0]))
    return last - min(starts)


WRITERS = {
    "seq": ["seq", "1", str(FLOOD_LINES)],
    # one write(2) a line, as a logger flushing each line to a terminal does
    "awk": ["awk", f"BEGIN {{ for (i = 1; i <= {FLOOD_LINES}; i++) {{ print i; fflush() }} }}"],
}


def flood_once(folder: Path, path: Path, name: str) -> tuple[float, float, int]:
    """(command to end, the flood itself, lines lost) for one tuilaunch run."""
    log_dir = folder / f"flood_log_{name}"
    shutil.rmtree(log_dir, ignore_errors=True)
    start = time.perf_counter()
    proc = tuilaunch(path, log_dir, out=subprocess.DEVNULL)
    proc.wait()  # a blocking wait: one with a timeout polls, and rounds the time up to 50 ms
    whole = time.perf_counter() - start
    logged = sum(sum(1 for _ in open(f, "rb")) for f in log_dir.glob("*/f*.log"))
    return whole, flood_window(log_dir), 4 * FLOOD_LINES - logged


def floor_flood_once(folder: Path, writer: list[str], tty: bool) -> float:
    """The same 4 writers straight to files, line-buffered as on a terminal, or not."""
    argv = ["stdbuf", "-oL"] if tty else []
    outs = [open(folder / f"direct{i}.txt", "wb") for i in range(4)]
    start = time.perf_counter()
    writers = [subprocess.Popen([*argv, *writer], stdout=out) for out in outs]
    for process in writers:
        process.wait()
    elapsed = time.perf_counter() - start
    for out in outs:
        out.close()
    return elapsed


def reader_flood_once(folder: Path, writer: list[str], tty: bool) -> float:
    """The same 4 writers through pipes, or pseudo-terminals set up as tuilaunch's (no
    output processing), each read by a minimal reader that writes what it reads to a file,
    nothing else: what the pipes or terminals themselves cost, under any launcher that
    reads them."""
    import pty
    import selectors
    import termios

    chooser = selectors.DefaultSelector()
    files: dict[int, int] = {}
    writers = []
    start = time.perf_counter()
    for i in range(4):
        master, slave = pty.openpty() if tty else os.pipe()
        if tty:
            attrs = termios.tcgetattr(slave)
            attrs[1] &= ~termios.OPOST
            termios.tcsetattr(slave, termios.TCSANOW, attrs)
        writers.append(subprocess.Popen(writer, stdout=slave, start_new_session=True))
        os.close(slave)
        os.set_blocking(master, False)
        files[master] = os.open(folder / f"read{i}.txt", os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        chooser.register(master, selectors.EVENT_READ)
    while files:
        for key, _ in chooser.select():
            try:
                chunk = os.read(key.fd, 1 << 16)
            except BlockingIOError:
                continue
            except OSError:  # EIO: the writer of a terminal is gone (a pipe says b"")
                chunk = b""
            if chunk:
                os.write(files[key.fd], chunk)
                continue
            chooser.unregister(key.fd)
            os.close(key.fd)
            os.close(files.pop(key.fd))
    for process in writers:
        process.wait()
    return time.perf_counter() - start


def flood(folder: Path, writer: str, tty: bool) -> tuple[float, float, float, float, int]:
    """4 writers through tuilaunch (pipes, or pseudo-terminals) against the floor and the
    minimal reader; best of 3 each, interleaved: (command to end, flood itself, floor,
    minimal reader, lines lost in any run)."""
    emulate = "True" if tty else "None"  # None: the default, pipes
    name = f"{writer}_{'tty' if tty else 'pipe'}"
    argv = WRITERS[writer]
    path = write_launch(folder, f"flood_{name}.py",
                        f"[ExecuteProcess(cmd={argv!r}, name=f'f{{i}}', "
                        f"emulate_tty={emulate}) for i in range(4)]")
    wholes, windows, floors, readers, lost = [], [], [], [], 0
    for _ in range(3):
        whole, window, missing = flood_once(folder, path, name)
        wholes.append(whole)
        windows.append(window)
        lost += missing
        floors.append(floor_flood_once(folder, argv, tty))
        readers.append(reader_flood_once(folder, argv, tty))
    return min(wholes), min(windows), min(floors), min(readers), lost


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
        spawn_once(folder, 10)  # warms the bytecode cache, as an installed copy has it
        print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; ros2 launch "
              "is not installed here: the floors stand in for it")
        for count in (10, 100):
            ours, floor, threads = spawn_time(folder, count)
            print(f"start {count:>3} processes: tuilaunch {ours:.3f} s (command to all "
                  f"started, best of {TRIES}), bare Python Popen loop {floor:.3f} s, "
                  f"ratio {ours / floor:.2f}x{' (target <= 2x)' if count == 100 else ''}; "
                  f"tuilaunch threads with {count} children: {threads}")
        for writer, tty, what in (
                ("awk", False, "a line a write (awk, fflush) through pipes (the default)"),
                ("seq", False, "`seq` (4 KB writes) through pipes (the default)"),
                ("awk", True, "a line a write (awk, fflush) through pseudo-terminals "
                 "(emulate_tty=True)"),
                ("seq", True, "`seq` (8 KB writes) through pseudo-terminals "
                 "(emulate_tty=True)")):
            whole, window, floor, reader, lost = flood(folder, writer, tty)
            target = " (target <= 1.5x)" if (writer, tty) == ("awk", False) else ""
            print(f"flood 4 x {FLOOD_LINES:,} lines, {what}, all logged: the flood "
                  f"{window:.3f} s (first start to last line logged), command to end "
                  f"{whole:.3f} s; the same writers straight to files {floor:.3f} s; ratio "
                  f"{window / floor:.2f}x{target}, command to end {whole / floor:.2f}x; "
                  f"lines lost: {lost}")
            print(f"  the same {'terminals' if tty else 'pipes'} read by a minimal reader "
                  f"(read, write to a file, nothing else): {reader:.3f} s, "
                  f"{reader / floor:.2f}x the floor; tuilaunch's flood is "
                  f"{window / reader:.2f}x that reader")
        print(f"CPU of tuilaunch with 100 quiet processes: {idle_cpu(folder):.2f}% of a core "
              "(target < 1%)")


if __name__ == "__main__":
    main()
