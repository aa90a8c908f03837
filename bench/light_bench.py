"""What a launch costs when it uses little, one run on this machine, each beside its floor.

1. Idle threads and memory (RSS) of the launcher running 100 plain processes (`sleep`, no
   ROS work), headless and as a detached session's server, against a floor: a bare Python
   script starting the same 100 with a `subprocess.Popen` loop; and whether rclpy is
   loaded into either (read from /proc/PID/maps).
2. The TUI's first frame: from the command's start in a tmux window of 80x24 to the launch
   tree on screen (the demo bringup), against a minimal Textual app showing a Tree in the
   same tmux, and whether any of the demo's processes had started by then (the tree comes
   first). Best and median of 5 each, interleaved so both see the same machine.

    python bench/light_bench.py
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
COUNT = 100
TRIES = 5
PLAIN = f"""from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(cmd=['sleep', '600'], name=f's{{i}}')
                              for i in range({COUNT})])
"""
FLOOR = f"""import subprocess, sys
ps = [subprocess.Popen(['sleep', '600']) for _ in range({COUNT})]
print('all', flush=True)
sys.stdin.readline()
[p.kill() for p in ps]
[p.wait() for p in ps]
"""
MINIMAL = """import sys
from textual.app import App
from textual.widgets import Tree
class Minimal(App):
    def compose(self):
        tree = Tree("minimal-tree-root")
        tree.root.add_leaf("a leaf")
        tree.root.expand()
        yield tree
Minimal().run()
"""


def status_of(pid: int) -> tuple[int, float]:
    """Threads and RSS in MB."""
    fields = dict(line.split(":", 1) for line in
                  Path(f"/proc/{pid}/status").read_text().splitlines() if ":" in line)
    return int(fields["Threads"]), int(fields["VmRSS"].split()[0]) / 1024


def has_rclpy(pid: int) -> bool:
    maps = Path(f"/proc/{pid}/maps").read_text()
    return "/rclpy/" in maps or "librcl.so" in maps


def settle(pid: int, seconds: float = 3.0) -> None:
    """Waits until the process has used no CPU for `seconds` (idle), or 30 s passed."""
    def cpu() -> int:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return int(fields[11]) + int(fields[12])

    end = time.monotonic() + 30
    last, since = cpu(), time.monotonic()
    while time.monotonic() < end:
        time.sleep(0.25)
        now = cpu()
        if now != last:
            last, since = now, time.monotonic()
        elif time.monotonic() - since >= seconds:
            return


def headless_idle(folder: Path, path: Path) -> tuple[int, float, bool]:
    env = {**os.environ, "ROS_LOG_DIR": str(folder / "log")}
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                            env=env, start_new_session=True)
    try:
        assert proc.stdout is not None
        started = 0
        while started < COUNT:
            line = proc.stdout.readline()
            if not line:
                raise RuntimeError("tuilaunch ended before every process started")
            started += "process started" in line
        settle(proc.pid)
        threads, rss = status_of(proc.pid)
        return threads, rss, has_rclpy(proc.pid)
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        proc.communicate(timeout=120)


def session_idle(folder: Path, path: Path) -> tuple[int, float, bool]:
    runtime = Path(tempfile.mkdtemp(prefix="tlb"))
    env = {**os.environ, "ROS_LOG_DIR": str(folder / "log"), "XDG_RUNTIME_DIR": str(runtime)}

    def tl(*args: str) -> str:
        done = subprocess.run([sys.executable, "-m", "tuilaunch", *args], env=env,
                              capture_output=True, text=True, timeout=120)
        if done.returncode != 0:
            raise RuntimeError(done.stderr)
        return done.stdout

    name = tl(str(path), "--detach", "--name", "lightbench").strip()
    try:
        tl("wait", name, f"s{COUNT - 1}-{COUNT}", "running", "--timeout", "60")
        pid = int(json.loads((runtime / "tuilaunch" / f"{name}.json").read_text())["pid"])
        settle(pid)
        threads, rss = status_of(pid)
        return threads, rss, has_rclpy(pid)
    finally:
        tl("stop", name)
        shutil.rmtree(runtime, ignore_errors=True)


def floor_idle() -> tuple[int, float]:
    floor = subprocess.Popen([sys.executable, "-c", FLOOR], stdin=subprocess.PIPE,
                             stdout=subprocess.PIPE, text=True)
    assert floor.stdout is not None and floor.stdin is not None
    floor.stdout.readline()
    settle(floor.pid)
    threads, rss = status_of(floor.pid)
    floor.stdin.write("\n")
    floor.stdin.close()
    floor.wait()
    return threads, rss


def first_frame(command: str, marker: str, folder: Path) -> tuple[float, str]:
    """Seconds from starting `command` in a detached 80x24 tmux window until `marker` is on
    its screen; and the screen then."""
    session = f"lightbench{os.getpid()}"
    socket = tempfile.mktemp(prefix="tmux", dir=folder)  # a server of its own each time
    tmux = ["tmux", "-S", socket]
    start = time.perf_counter()
    subprocess.run([*tmux, "new-session", "-d", "-s", session, "-x", "80", "-y", "24",
                    command], check=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            screen = subprocess.run([*tmux, "capture-pane", "-p", "-t", session],
                                    capture_output=True, text=True).stdout
            if marker in screen:
                return time.perf_counter() - start, screen
            time.sleep(0.005)
        raise RuntimeError(f"{marker!r} never came on screen")
    finally:
        subprocess.run([*tmux, "kill-server"], capture_output=True)


def tui_first_frame(folder: Path) -> tuple[float, float, float, float, bool]:
    """Best and median first frame of tuilaunch and the minimal app (interleaved), and
    whether tuilaunch had started a process when its tree first showed.

    Both as installed: with their bytecode cached (in a folder of the run's, not the
    source tree), after one untimed start of each."""
    minimal = folder / "minimal.py"
    minimal.write_text(MINIMAL)
    python = f"env -u PYTHONDONTWRITEBYTECODE PYTHONPYCACHEPREFIX={folder / 'pyc'} " \
        f"{sys.executable}"
    ours: list[float] = []
    floors: list[float] = []
    started_first = False
    for attempt in range(-1, TRIES):
        runtime = folder / f"run{attempt}"
        runtime.mkdir()
        log_dir = folder / f"tui_log{attempt}"
        command = (f"env XDG_RUNTIME_DIR={runtime} ROS_LOG_DIR={log_dir} "
                   f"{python} -m tuilaunch {ROOT / 'examples' / 'bringup.py'}")
        elapsed, screen = first_frame(command, "▼ bringup.py", folder)
        # the screen at the first sight of the tree: a state other than waiting means a
        # process ran before the tree was drawn
        started_first |= any(word in screen for word in ("running", "exited"))
        wait_gone(log_dir)
        floor = first_frame(f"{python} {minimal}", "a leaf", folder)[0]
        if attempt >= 0:  # -1: the bytecode is written
            ours.append(elapsed)
            floors.append(floor)
    return (min(ours), statistics.median(ours), min(floors), statistics.median(floors),
            started_first)


def processes_of(log_dir: Path) -> list[int]:
    """The TUI, its server and their nodes: every process whose ROS_LOG_DIR is `log_dir`."""
    wanted = f"ROS_LOG_DIR={log_dir}".encode()
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if wanted in (entry / "environ").read_bytes().split(b"\0"):
                    found.append(int(entry.name))
            except OSError:
                continue
    return found


def wait_gone(log_dir: Path) -> None:
    """tmux's hang-up makes the TUI stop its launch: waits for that, then stops what is left
    (SIGTERM to the server stops its nodes; SIGKILL to whatever ignores it)."""
    for sig in (signal.SIGTERM, signal.SIGKILL, None):
        end = time.monotonic() + 30
        while (left := processes_of(log_dir)) and time.monotonic() < end:
            time.sleep(0.2)
        if not left or sig is None:
            return
        for pid in left:
            try:
                os.kill(pid, sig)
            except ProcessLookupError:
                pass


def main() -> None:
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        path = folder / "plain.py"
        path.write_text(PLAIN)
        floor_threads, floor_rss = floor_idle()
        head_threads, head_rss, head_ros = headless_idle(folder, path)
        server_threads, server_rss, server_ros = session_idle(folder, path)
        print(f"{COUNT} plain processes, idle: floor (Popen loop) {floor_threads} thread(s), "
              f"{floor_rss:.1f} MB")
        print(f"  tuilaunch --headless: {head_threads} threads, {head_rss:.1f} MB "
              f"({head_rss / floor_rss:.2f}x the floor), rclpy loaded: {head_ros}")
        print(f"  session server (--detach): {server_threads} threads, {server_rss:.1f} MB "
              f"({server_rss / floor_rss:.2f}x the floor), rclpy loaded: {server_ros}")
        best, median, floor_best, floor_median, started_first = tui_first_frame(folder)
        print(f"TUI first frame (tmux 80x24, command to the tree on screen, demo bringup): "
              f"best {best:.3f} s, median {median:.3f} s; minimal Textual app with a Tree: "
              f"best {floor_best:.3f} s, median {floor_median:.3f} s; ratio "
              f"{best / floor_best:.2f}x (best), {median / floor_median:.2f}x (median); a "
              f"process had started before the tree showed: {started_first}")


if __name__ == "__main__":
    main()
