"""Session figures, one run on this machine, each beside its in-process counterpart.

1. Keypress-to-screen latency (median of medians and worst over 2 x 40 presses) while
   4 processes flood output as fast as they can (`yes`): the TUI as a client of a session
   server (the default since sessions) against the TUI running the supervisor in its own process
   (the previous design). Measured end to end on a pseudo-terminal: from writing the key
   `l` until the output pane's status line, redrawn, names the new level.
2. Time for `tuilaunch attach` to show its first screen on a session whose 4 processes
   have written 1,000,000 lines each (the panes are filled from the log files' tails),
   against attaching to a session with empty logs.
3. Round trip of `tuilaunch status --json` (a fresh Python process each time), against
   `python -c pass`.

    python bench/session_bench.py             (everything)
    python bench/session_bench.py latency 3   (only 1., 3 alternated rounds)
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from run_bench import write_launch  # bench/ is on sys.path when run as a script
from tui_bench import Terminal, latency

from tuilaunch.engine.packages import ensure_environment

IN_PROCESS = ("import sys; from pathlib import Path; from tuilaunch.tui.app import make_app; "
              "make_app(sys.argv[1], {}, Path(sys.argv[2])).run()")


def tl(*args: str) -> str:
    return subprocess.run([sys.executable, "-m", "tuilaunch", *args], capture_output=True,
                          text=True, check=True).stdout


def attach_time(path: Path, lines: int) -> float:
    name = tl(str(path), "--detach").strip()
    try:
        log_dir = Path(json.loads(tl("status", name, "--json"))["log_dir"])
        while sum(f.stat().st_size for f in log_dir.glob("p*.log")) < lines * 4 * 8:
            time.sleep(0.2)  # until the printers are done ("line N\n" is 8+ bytes)
        term = Terminal([sys.executable, "-m", "tuilaunch", "attach", name], size=(80, 24))
        try:
            return term.read_until(b"4 running")
        finally:
            term.close(b"d")
    finally:
        tl("stop", name)


def main() -> None:
    """`session_bench.py latency [ROUNDS]` measures only the keypress latency."""
    only_latency = sys.argv[1:2] == ["latency"]
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    ensure_environment()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    with tempfile.TemporaryDirectory(prefix="tlb") as name:
        folder = Path(name)
        os.environ["XDG_RUNTIME_DIR"] = str(folder)
        os.environ["ROS_LOG_DIR"] = str(folder / "log")
        flood = write_launch(folder, "flood.py", "[ExecuteProcess(cmd=['yes', 'flooding the "
                            "pane with a line of text'], name=f'flood{i}') for i in range(4)]")
        # alternated, so both designs share whatever else the machine is doing
        client: list[tuple[float, float]] = []
        inside: list[tuple[float, float]] = []
        for _ in range(rounds):
            client.append(latency([sys.executable, "-m", "tuilaunch", str(flood)], size=(80, 24)))
            inside.append(latency([sys.executable, "-c", IN_PROCESS, str(flood),
                                   str(folder / "inproc")], size=(80, 24)))
        c_med, c_max = statistics.median(m for m, _ in client), max(w for _, w in client)
        i_med, i_max = statistics.median(m for m, _ in inside), max(w for _, w in inside)
        print(f"keypress latency under 4 floods, TUI as a session client: median "
              f"{c_med:.1f} ms, worst {c_max:.1f} ms (target: worst < 100 ms)")
        print(f"keypress latency under 4 floods, supervisor in the TUI process: median "
              f"{i_med:.1f} ms, worst {i_max:.1f} ms (client/in-process worst: "
              f"{c_max / i_max:.2f}x)")
        print(f"(load average while measuring: {os.getloadavg()[0]:.1f} on "
              f"{os.cpu_count()} cores)")
        if only_latency:
            return
        count = 1_000_000
        big = write_launch(folder, "big.py", f"[ExecuteProcess(cmd=['sh', '-c', 'seq {count} "
                          f"| sed s/^/line/; sleep 600'], name=f'p{{i}}') for i in range(4)]")
        empty = write_launch(folder, "empty.py", "[ExecuteProcess(cmd=['sleep', '600'], "
                            "name=f'p{i}') for i in range(4)]")
        full = attach_time(big, count)
        bare = attach_time(empty, 0)
        print(f"attach to first screen: 4 logs of {count:,} lines {full:.2f} s, empty logs "
              f"{bare:.2f} s ({full / bare:.1f}x)")
        quiet = tl(str(empty), "--detach").strip()
        try:
            runs = []
            for _ in range(5):
                start = time.perf_counter()
                tl("status", quiet, "--json")
                runs.append(time.perf_counter() - start)
            floor = []
            for _ in range(5):
                start = time.perf_counter()
                subprocess.run([sys.executable, "-c", "pass"], check=True)
                floor.append(time.perf_counter() - start)
        finally:
            tl("stop", quiet)
        s, f = statistics.median(runs), statistics.median(floor)
        print(f"tuilaunch status --json: {s * 1000:.0f} ms, python -c pass {f * 1000:.0f} ms "
              f"({s / f:.1f}x: importing tuilaunch)")


if __name__ == "__main__":
    main()
