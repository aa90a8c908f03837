"""TUI figures, one run on this machine, each beside its floor.

1. Bytes on the wire: what each program writes to an 80x24 (and 120x40) terminal per second,
   read from a pseudo-terminal as a terminal would: tuilaunch running the demo bringup
   (its all-nodes pane shows every line), the same with every node stopped, and under 4
   flooding processes; beside `ros2 launch -a`'s stand-in (ros2 launch is not installed
   here: `tuilaunch --headless` prints the same demo as plain `[id] line` lines, as
   `ros2 launch` does) and htop (default 1.5 s refresh) measured in the same run; and with
   the Topics tab open (the topic list refreshed every 3 s, rates of the rows on screen once
   a second).
2. Keypress-to-screen latency (median and worst over 40 presses) while 4 processes flood
   output as fast as they can (`yes`), against the same with 4 quiet processes (target:
   worst under 100 ms). Measured end to end on a pseudo-terminal: from writing the key `l`
   until the output pane's status line, redrawn, names the new level.
3. Memory of the TUI with 100 processes and full scrollbacks (5000 lines each).
4. Time to first screen on a real pseudo-terminal, against a minimal Textual app's.

    python bench/tui_bench.py            # everything
    python bench/tui_bench.py --topics   # only the wire with the Topics tab open, and htop
"""

from __future__ import annotations

import asyncio
import fcntl
import os
import pty
import select
import shutil
import statistics
import struct
import subprocess
import sys
import tempfile
import termios
import time
from pathlib import Path

from run_bench import write_launch  # bench/ is on sys.path when run as a script

from tuilaunch.engine.packages import ensure_environment
from tuilaunch.tui.app import launch_app
from tuilaunch.tui.output_store import View


class Terminal:
    """A program on a pseudo-terminal, its output read continuously as a terminal would."""

    def __init__(self, argv: list[str], log_dir: Path | None = None,
                 size: tuple[int, int] = (100, 30)) -> None:
        self.master, slave = pty.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", size[1], size[0], 0, 0))
        env = {**os.environ, "TERM": "xterm-256color",
               "COLUMNS": str(size[0]), "LINES": str(size[1])}
        if log_dir is not None:  # else the program's own (a session's, for attach)
            env["ROS_LOG_DIR"] = str(log_dir)
        self.proc = subprocess.Popen(argv, stdin=slave, stdout=slave, stderr=slave, env=env,
                                     start_new_session=True)
        os.close(slave)
        self.seen = b""

    def read_until(self, marker: bytes, limit: float = 30.0) -> float:
        """Seconds until `marker` appears in what is printed from now on."""
        start = time.perf_counter()
        window = b""
        while marker not in window:
            if time.perf_counter() - start > limit:
                raise AssertionError(f"{marker!r} never appeared")
            if select.select([self.master], [], [], 0.05)[0]:
                window = window[-4096:] + os.read(self.master, 1 << 20)
        return time.perf_counter() - start

    def press(self, key: bytes) -> None:
        os.write(self.master, key)

    def rate(self, seconds: float) -> float:
        """Bytes per second written to the terminal over the next `seconds`."""
        count = 0
        end = time.perf_counter() + seconds
        while (left := end - time.perf_counter()) > 0:
            if select.select([self.master], [], [], min(left, 0.1))[0]:
                try:
                    count += len(os.read(self.master, 1 << 20))
                except OSError:
                    break
        return count / seconds

    def settle(self, seconds: float) -> None:
        self.rate(seconds)

    def close(self, key: bytes | None = None) -> None:
        """Ends the program: with `key` typed (e.g. `d` to detach), else SIGTERM."""
        if key is not None:
            os.write(self.master, key)
        else:
            self.proc.terminate()
        try:
            while self.proc.poll() is None:
                if select.select([self.master], [], [], 0.2)[0]:
                    os.read(self.master, 1 << 20)
        except OSError:
            pass
        self.proc.wait(timeout=60)
        os.close(self.master)


TUI = [sys.executable, "-m", "tuilaunch"]
WINDOW = 10.0  # seconds each rate is measured over


def tui_rates(path: Path, log_dir: Path, size: tuple[int, int]) -> tuple[float, float]:
    """tuilaunch with the demo: bytes/s while it runs, then with every node stopped."""
    term = Terminal([*TUI, str(path)], log_dir, size)
    try:
        term.read_until(b"5 running", limit=60)
        term.settle(3.0)  # the actions finish, the first screen is out
        running = term.rate(WINDOW)
        term.press(b"s")  # on the root row: stop everything (it asks first)
        term.settle(0.5)
        term.press(b"y")
        term.read_until(b"5 exited", limit=60)
        term.settle(2.0)
        stopped = term.rate(WINDOW)
    finally:
        term.close()
    return running, stopped


def topics_rate(path: Path, log_dir: Path, size: tuple[int, int]) -> float:
    """tuilaunch with the demo and its Topics tab open: bytes/s once the rates show."""
    term = Terminal([*TUI, str(path)], log_dir, size)
    try:
        term.read_until(b"5 running", limit=60)
        term.settle(3.0)
        term.press(b"5")
        term.read_until(b" Hz", limit=60)  # a rate measured for a row on screen
        term.settle(3.0)  # the list refreshed once more
        return term.rate(WINDOW)
    finally:
        term.close()


def topics_wire(folder: Path) -> None:
    bringup = Path(__file__).resolve().parent.parent / "examples" / "bringup.py"
    htop = rate_of(["htop"], folder / "t0", None, (80, 24)) if shutil.which("htop") else None
    topics = topics_rate(bringup, folder / "t1", (80, 24))
    running, _ = tui_rates(bringup, folder / "t2", (80, 24))
    htop_text = f"{htop:,.0f} B/s" if htop is not None else "not installed"
    ratio = f" ({topics / htop:.1f}x htop)" if htop else ""
    print("bytes to the terminal at 80x24, the demo running")
    print(f"  Topics tab open:     tuilaunch {topics:,.0f} B/s{ratio}, htop {htop_text}")
    print(f"  Nodes tab (CPU/mem sampled): tuilaunch {running:,.0f} B/s")


def rate_of(argv: list[str], log_dir: Path, marker: bytes | None, size: tuple[int, int],
            settle: float = 3.0) -> float:
    term = Terminal(argv, log_dir, size)
    try:
        if marker is not None:
            term.read_until(marker, limit=60)
        term.settle(settle)
        return term.rate(WINDOW)
    finally:
        term.close()


def wire(folder: Path, flood: Path) -> None:
    bringup = Path(__file__).resolve().parent.parent / "examples" / "bringup.py"
    headless = [*TUI, "--headless", str(bringup)]
    stand_in = rate_of(headless, folder / "w0", b"Publishing", (80, 24))
    htop = rate_of(["htop"], folder / "w1", None, (80, 24)) if shutil.which("htop") else None
    running, stopped = tui_rates(bringup, folder / "w2", (80, 24))
    wide, _ = tui_rates(bringup, folder / "w3", (120, 40))
    flood_tui = rate_of([*TUI, str(flood)], folder / "w4", b"4 running", (80, 24))
    flood_plain = rate_of([*TUI, "--headless", str(flood)], folder / "w5", b"flooding",
                          (80, 24), settle=1.0)

    def vs(value: float, floor: float | None) -> str:
        return f"{value / floor:.1f}x" if floor else "n/a"

    htop_text = f"{htop:,.0f} B/s" if htop is not None else "not installed"
    topics = topics_rate(bringup, folder / "w6", (80, 24))
    print("bytes to the terminal, 80x24 unless said (ros2 launch -a stand-in: "
          "tuilaunch --headless, plain [id] lines)")
    print(f"  demo running:        tuilaunch {running:,.0f} B/s (target <= 2,000), stand-in "
          f"{stand_in:,.0f} B/s ({vs(running, stand_in)}), htop {htop_text} "
          f"({vs(running, htop)})")
    print(f"  demo at 120x40:      tuilaunch {wide:,.0f} B/s")
    print(f"  Topics tab open:     tuilaunch {topics:,.0f} B/s, htop {htop_text} "
          f"({vs(topics, htop)})")
    print(f"  every node stopped:  tuilaunch {stopped:,.0f} B/s (target <= 300), stand-in 0 "
          f"B/s, htop {htop_text} ({vs(stopped, htop)})")
    print(f"  4 flooders (yes):    tuilaunch {flood_tui:,.0f} B/s, stand-in "
          f"{flood_plain:,.0f} B/s (tuilaunch writes {vs(flood_plain, flood_tui)} less)")


LEVEL_WORDS = ("INFO", "WARN", "ERROR", "FATAL", "DEBUG")


def latency(argv: list[str], log_dir: Path | None = None, size: tuple[int, int] = (100, 30),
            presses: int = 40) -> tuple[float, float]:
    """Median and worst ms from a key to its redraw, for the TUI that `argv` starts: key `l`
    cycles the level filter, and its new name in the status line is the redraw."""
    term = Terminal(argv, log_dir, size)
    try:
        term.read_until(b"4 running", limit=60)
        time.sleep(1.0)  # the flood at its steady state
        times = []
        for i in range(presses):
            term.press(b"l")
            word = LEVEL_WORDS[i % len(LEVEL_WORDS)].encode()
            times.append(term.read_until(b"  " + word + b"+"))
            time.sleep(0.05)
    finally:
        term.close()
    return statistics.median(times) * 1000, max(times) * 1000


def rss_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


async def memory(path: Path, log_dir: Path, count: int, lines: int) -> tuple[float, int]:
    """The TUI's RSS growth once every process has printed all its lines (the log files
    say so), and how many lines the scrollbacks then hold. The TUI runs as `tuilaunch
    FILE` runs it (launch_app): the launch is in its session server, a process of its
    own, so this is the client's memory."""
    before = rss_mb()
    app = launch_app(str(path), {}, log_dir, scrollback=5000)
    async with app.run_test(size=(100, 30)) as pilot:
        deadline = time.monotonic() + 300
        while app.supervisor is None:  # the server starts once the tree shows
            assert time.monotonic() < deadline, "the session never started"
            await pilot.pause(0.2)

        def logged() -> int:
            return sum(sum(1 for _ in open(f)) for f in log_dir.glob("n*.log"))

        while logged() < count * lines:
            assert time.monotonic() < deadline, "the printers never finished"
            await pilot.pause(1.0)
        await pilot.pause(1.0)  # the last drain ticks
        held = sum(len(app.store.lines(View(p))) for p in app.supervisor.states)
        used = rss_mb() - before
        await app.engine.run(app.supervisor.shutdown("bench over"))
    if app.server_process is not None:
        app.server_process.wait(timeout=120)
    return used, held


def first_screen(argv: list[str], marker: bytes) -> float:
    master, slave = pty.openpty()
    start = time.perf_counter()
    proc = subprocess.Popen(argv, stdin=slave, stdout=slave, stderr=slave,
                            env={**os.environ, "TERM": "xterm-256color"},
                            start_new_session=True)
    os.close(slave)
    seen = b""
    while marker not in seen:
        if select.select([master], [], [], 30)[0]:
            seen += os.read(master, 65536)
        else:
            raise AssertionError(f"no first screen from {argv}")
    elapsed = time.perf_counter() - start
    proc.terminate()
    try:
        while select.select([master], [], [], 0.2)[0]:
            os.read(master, 65536)
    except OSError:
        pass
    proc.wait(timeout=60)
    os.close(master)
    return elapsed


MINIMAL = """
from textual.app import App
from textual.widgets import Static
class Minimal(App):
    def compose(self):
        yield Static("minimal first screen")
Minimal().run()
"""


def main() -> None:
    ensure_environment()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    os.environ.setdefault("ROS_DOMAIN_ID", str(150 + os.getpid() % 50))
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        if sys.argv[1:] == ["--topics"]:
            topics_wire(folder)
            return
        flood = write_launch(folder, "flood.py", "[ExecuteProcess(cmd=['yes', 'flooding the "
                            "pane with a line of text'], name=f'flood{i}') for i in range(4)]")
        quiet = write_launch(folder, "quiet.py", "[ExecuteProcess(cmd=['sleep', '600'], "
                            "name=f'quiet{i}') for i in range(4)]")
        wire(folder, flood)
        q_med, q_max = latency([*TUI, str(quiet)], folder / "q")
        f_med, f_max = latency([*TUI, str(flood)], folder / "f")
        print(f"keypress latency, 4 quiet processes:    median {q_med:.1f} ms, "
              f"worst {q_max:.1f} ms")
        print(f"keypress latency, 4 flooding processes: median {f_med:.1f} ms, "
              f"worst {f_max:.1f} ms (target: worst < 100 ms)")
        printer = folder / "printer.py"
        printer.write_text("import time\nfor i in range(6000):\n"
                           "    print(f'[INFO] [bench]: line {i} of a typical node log', "
                           "flush=True)\n    if i % 3 == 0:\n        time.sleep(0.01)\n"
                           "time.sleep(600)\n")
        hundred = write_launch(folder, "hundred.py", f"[ExecuteProcess(cmd=['{sys.executable}', "
                              f"'{printer}'], name=f'n{{i}}') for i in range(100)]")
        used, held = asyncio.run(memory(hundred, folder / "m", 100, 6000))
        print(f"memory of the TUI with 100 processes after 6000 lines each (scrollback 5000 "
              f"per process, {held} lines held): {used:.0f} MB over the Python process "
              "before the app")
        waiting = folder / "one.py"
        waiting.write_text(
            "from simple_launch import SimpleLauncher\n"
            "from simple_launch.events import When\n"
            "def generate_launch_description():\n"
            "    sl = SimpleLauncher()\n"
            "    with sl.group(when=When(delay=600.0)):\n"
            "        sl.node('tuilaunch_demos', 'talker')\n"
            "    return sl.launch_description()\n")
        ours = first_screen([sys.executable, "-m", "tuilaunch", str(waiting)], b"1 waiting")
        minimal_script = folder / "minimal.py"
        minimal_script.write_text(MINIMAL)
        floor = first_screen([sys.executable, str(minimal_script)], b"minimal first screen")
        print(f"time to first screen: tuilaunch {ours:.2f} s, minimal Textual app "
              f"{floor:.2f} s (ratio {ours / floor:.1f}x)")


if __name__ == "__main__":
    main()
