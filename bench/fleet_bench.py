"""A fleet TUI's cost: `tuilaunch attach robot1:s1 ... robot1:sN` for N = 1, 2, 4.

N sessions of the same small launch (a node printing a line a second, one sleeping) run on
"robot1" (a real sshd on 127.0.0.1, tests/integration/sshd.py); one fleet TUI at 80x24 follows them
all, each over its own ssh link. Measured side by side in one run, for each N:
  - the bytes a second crossing the ssh links, idle (counted on the TCP connections by
    remote_bench.py's relay as ssh's ProxyCommand: encrypted, keep-alives included), and
    that figure over N = 1's: the issue expects about N times;
  - the first frame: seconds from the command's start until every session's root shows its
    live counts (`2 running`) on the terminal.

    python bench/fleet_bench.py
"""

from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from remote_bench import Link  # noqa: E402  (bench/ is on sys.path as a script)

from tests.integration.sshd import Machines  # noqa: E402  (the tests' sshd)

WINDOW = 10.0  # seconds each rate is measured over
SIZES = (1, 2, 4)
LAUNCH = """
from simple_launch import SimpleLauncher
from launch.actions import ExecuteProcess
def generate_launch_description():
    sl = SimpleLauncher()
    sl.add_action(ExecuteProcess(name='ticker', cmd=[
        'sh', '-c', 'i=0; while true; do i=$((i+1)); echo tick $i; sleep 1; done']))
    sl.add_action(ExecuteProcess(name='quiet', cmd=['sleep', '3600']))
    return sl.launch_description()
"""


def start_sessions(machines: Machines, path: Path, count: int) -> None:
    robot = machines["robot1"]
    env = {**os.environ, "XDG_RUNTIME_DIR": str(robot.runtime),
           "ROS_LOG_DIR": str(robot.folder / "roslog")}
    for i in range(1, count + 1):
        subprocess.run([sys.executable, "-m", "tuilaunch", str(path), "--detach", "--name",
                        f"s{i}"], env=env, check=True, capture_output=True)
        subprocess.run([sys.executable, "-m", "tuilaunch", "wait", f"s{i}", "ticker-1",
                        "running", "--timeout", "60"], env=env, check=True,
                       capture_output=True)


def screen(session: str) -> str:
    return subprocess.run(["tmux", "capture-pane", "-p", "-t", session], capture_output=True,
                          text=True).stdout


FLEET = "from tuilaunch.tui.fleet.app import FleetApp; FleetApp({members!r}).run()"
"""The fleet TUI over `members`, as `tuilaunch attach a b ...` runs it (a fleet of one
too, which the command line opens as the single-session TUI)."""


def measure(count: int, link: Link, remote: str, single: bool = False) -> tuple[float, float]:
    """The first frame with every root's counts (s), and the idle link bytes/s. The TUI
    runs in tmux at 80x24, whose screen is read as the operator sees it. `single`: the
    single-session TUI (`tuilaunch attach robot1:s1`) instead, the reference."""
    tag = f"fleet{count}{'single' if single else ''}"
    session = f"tlfleet{os.getpid()}"
    env = {"TUILAUNCH_SSH_COMMAND": link.ssh(tag), "TUILAUNCH_REMOTE": remote}
    members = [("robot1", f"s{i}") for i in range(1, count + 1)]
    program = ["-m", "tuilaunch", "attach", "robot1:s1"] if single else \
        ["-c", shlex.quote(FLEET.format(members=members))]
    command = " ".join([*(f"{k}={shlex.quote(v)}" for k, v in env.items()),
                        shlex.quote(sys.executable), *program])
    start = time.perf_counter()
    subprocess.run(["tmux", "new", "-d", "-s", session, "-x", "80", "-y", "24", command],
                   check=True)
    try:
        roots = ["[robot1:s1]"] if single else [f"robot1:s{i} " for i in range(1, count + 1)]
        while not all(any(r in line and "2 running" in line for line in
                          screen(session).splitlines()) for r in roots):
            if time.perf_counter() - start > 120:
                raise AssertionError(f"never saw every root:\n{screen(session)}")
            time.sleep(0.02)
        first = time.perf_counter() - start
        time.sleep(5.0)  # the replay and the first screens are out
        before = link.count(tag)
        time.sleep(WINDOW)
        rate = (link.count(tag) - before) / WINDOW
    finally:
        subprocess.run(["tmux", "send-keys", "-t", session, "d" if single else "q"],
                       capture_output=True)
        time.sleep(2)
        subprocess.run(["tmux", "kill-session", "-t", session], capture_output=True)
    return first, rate


def main() -> None:
    from tuilaunch.engine.packages import ensure_environment

    ensure_environment()
    folder = Path(tempfile.mkdtemp(prefix="tlfleet"))
    machines = Machines(folder / "ssh", aliases=("robot1",))
    remote = f"{shlex.quote(sys.executable)} -m tuilaunch"
    link = Link(machines, folder, machines["robot1"].port)
    path = folder / "test_launch.py"
    path.write_text(LAUNCH)
    rows = []
    try:
        start_sessions(machines, path, max(SIZES))
        single = measure(1, link, remote, single=True)
        for count in SIZES:
            rows.append((count, *measure(count, link, remote)))
    finally:
        machines.stop()
    one = rows[0][2]
    print("a fleet TUI at 80x24 over N sessions on robot1, each session its own ssh link")
    print(f"  {'N':>3}{'first frame, every root':>26}{'idle link':>14}{'over N=1':>10}")
    for count, first, rate in rows:
        print(f"  {count:>3}{first:>24.2f} s{rate:>10,.0f} B/s{rate / max(one, 1):>9.2f}x")
    print(f"  the single-session TUI on s1: first frame {single[0]:.2f} s, idle link "
          f"{single[1]:,.0f} B/s")
    print(json.dumps({**{str(c): {"first_frame_s": f, "idle_bytes_per_s": r}
                         for c, f, r in rows},
                      "single": {"first_frame_s": single[0], "idle_bytes_per_s": single[1]}}))


if __name__ == "__main__":
    main()
