"""Bytes crossing the ssh link for a TUI on a session on another machine, one run.

Side by side, at 80x24, with the demo (examples/bringup.py) running as a session on
"robot1" (a real sshd on 127.0.0.1, from tests/integration/sshd.py):
  - `tuilaunch attach robot1:NAME`: the TUI here, only the session protocol crosses;
  - `ssh -t robot1 tuilaunch attach NAME`: the same TUI drawn over ssh, as without it.
Each idle (the demo alone) and under a flood (the demo and a node printing 2,000 lines a
second), the latter twice: with the all-nodes pane, and with the talker's pane shown (the
flood then off screen: only the pane shown is sent; the drawn TUI draws what it shows).
ros2 launch has no attach over a link: ssh drawing the TUI is the reference here. The
bytes are counted on the TCP connection itself (ssh's ProxyCommand is a relay
that counts), so they are what crosses the link: encrypted, with ssh's own keep-alives.
Also: the time to attach, from the command's start to the first node line on screen.

    python bench/remote_bench.py
"""

from __future__ import annotations

import json
import os
import select
import shlex
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from tui_bench import Terminal  # noqa: E402  (bench/ is on sys.path as a script)

from tests.integration.sshd import Machines  # noqa: E402  (the tests' sshd, as the issue asks)

WINDOW = 10.0  # seconds each rate is measured over
MARKERS = {"demo": b"says hi", "flood": b"of the lidar"}
"""A node's line on screen: the talker's; under the flood, the flooder's (what a screen
showing the newest lines shows)."""

TALKER_ROW = b"\x1b[B" * 3
"""Down the tree from its first row to talker-1: its pane is shown (one write)."""

FLOODER = """
    from launch.actions import ExecuteProcess
    sl.add_action(ExecuteProcess(name='flood', cmd=[{python!r}, '-c', {code!r}]))
    return sl.launch_description()
"""
FLOOD_CODE = ("import time\ni = 0\nwhile True:\n    for _ in range(200):\n"
              "        i += 1\n        print(f'[INFO] [{time.time():.6f}] [flood]: "
              "reading {i} of the lidar, all is fine', flush=False)\n"
              "    print(end='', flush=True)\n    time.sleep(0.1)\n")


def relay(host: str, port: int, counter: str) -> None:
    """ssh's ProxyCommand: stdin/stdout <-> TCP, the bytes both ways written to `counter`."""
    sock = socket.create_connection((host, port))
    # a file per connection: a reconnection (or a second connection) adds, never overwrites
    counter = counter.replace(".bytes", f"-{os.getpid()}.bytes")
    total = 0
    last = 0.0
    streams = [sys.stdin.fileno(), sock]
    while True:
        ready = select.select(streams, [], [], 0.2)[0]
        for stream in ready:
            if stream is sock:
                data = sock.recv(1 << 16)
                if not data:
                    return
                os.write(sys.stdout.fileno(), data)
            else:
                data = os.read(stream, 1 << 16)
                if not data:
                    return
                sock.sendall(data)
            total += len(data)
        if time.monotonic() - last > 0.1:
            last = time.monotonic()
            # written aside and renamed: a reader never sees the file emptied for the write
            # (read as 0, it added a link's whole total to a rate: 1 run in 6 under load)
            Path(counter + ".new").write_text(str(total))
            os.replace(counter + ".new", counter)


class Link:
    """The ssh command line, through the counting relay, and the bytes counted so far."""

    def __init__(self, machines: Machines, folder: Path, port: int) -> None:
        self.counters = folder
        self.port = port
        self.machines = machines

    def ssh(self, tag: str) -> str:
        counter = self.counters / f"{tag}.bytes"
        proxy = f"{shlex.quote(sys.executable)} {shlex.quote(__file__)} __relay 127.0.0.1 " \
            f"{self.port} {counter}"
        return f"{self.machines.ssh_command} -o {shlex.quote('ProxyCommand=' + proxy)}"

    def count(self, tag: str) -> int:
        total = 0
        # the tag's connections only (`fleet1-PID`), not another tag it begins
        # (`fleet1single-PID`)
        for path in self.counters.glob(f"{tag}-*.bytes"):
            try:
                total += int(path.read_text() or 0)
            except ValueError:
                pass
        return total


def measure(argv: list[str], env: dict[str, str], link: Link, tag: str, marker: bytes,
            keys: bytes = b"") -> tuple[float, float]:
    """Seconds to the first node line, and link bytes/s over WINDOW once settled (after
    `keys`, typed as one write once the first node line is on screen)."""
    saved = dict(os.environ)
    os.environ.update(env)
    try:
        start = time.perf_counter()
        term = Terminal(argv, size=(80, 24))
    finally:
        os.environ.clear()
        os.environ.update(saved)
    try:
        term.read_until(marker, limit=90)
        attach = time.perf_counter() - start
        if keys:
            term.press(keys)
        term.settle(5.0)  # the first screen and the replay are out
        before = link.count(tag)
        term.rate(WINDOW)  # the terminal is read meanwhile, as a terminal would
        rate = (link.count(tag) - before) / WINDOW
    finally:
        term.close(b"d")
    return attach, rate


def start_session(machines: Machines, path: Path, name: str) -> None:
    robot = machines["robot1"]
    env = {**os.environ, "XDG_RUNTIME_DIR": str(robot.runtime),
           "ROS_LOG_DIR": str(robot.folder / "roslog")}
    subprocess.run([sys.executable, "-m", "tuilaunch", str(path), "--detach", "--name", name],
                   env=env, check=True, capture_output=True)
    subprocess.run([sys.executable, "-m", "tuilaunch", "wait", name, "talker-1", "running",
                    "--timeout", "60"], env=env, check=True, capture_output=True)


def main() -> None:
    from tuilaunch.engine.packages import ensure_environment

    ensure_environment()
    folder = Path(tempfile.mkdtemp(prefix="tlremote"))
    machines = Machines(folder / "ssh", aliases=("robot1",))
    remote = f"{shlex.quote(sys.executable)} -m tuilaunch"
    link = Link(machines, folder, machines["robot1"].port)
    bringup = ROOT / "examples" / "bringup.py"
    flood = folder / "flood_launch.py"
    # the demo, and a node printing fast beside it
    flood.write_text(bringup.read_text().replace(
        "\n    return sl.launch_description()\n",
        FLOODER.format(python=sys.executable, code=FLOOD_CODE)))
    rows = []
    try:
        # the flood twice: the all-nodes pane, then the talker's pane (3 rows down the
        # tree), where the flood is not on screen
        for name, path, session, keys in (("demo", bringup, "demo", b""),
                                          ("flood", flood, "flood", b""),
                                          ("focused", flood, "flood", TALKER_ROW)):
            if name != "focused":
                start_session(machines, path, session)
            ours = measure(
                [sys.executable, "-m", "tuilaunch", "attach", f"robot1:{session}"],
                {"TUILAUNCH_SSH_COMMAND": link.ssh(f"ours-{name}"),
                 "TUILAUNCH_REMOTE": remote}, link, f"ours-{name}",
                MARKERS[session], keys)
            drawn = measure(
                [*shlex.split(link.ssh(f"drawn-{name}")), "-t", "robot1",
                 f"{remote} attach {session}"], {}, link, f"drawn-{name}", MARKERS[session],
                keys)
            # the same with ssh's compression, which our link always asks for
            squeezed = measure(
                [*shlex.split(link.ssh(f"drawnc-{name}")), "-C", "-t", "robot1",
                 f"{remote} attach {session}"], {}, link, f"drawnc-{name}",
                MARKERS[session], keys)
            rows.append((name, ours, drawn, squeezed))
            if name != "flood":
                subprocess.run([sys.executable, "-m", "tuilaunch", "stop",
                                f"robot1:{session}"],
                               env={**os.environ, "TUILAUNCH_SSH_COMMAND": machines.ssh_command,
                                    "TUILAUNCH_REMOTE": remote}, capture_output=True)
    finally:
        machines.stop()
    print("bytes/s crossing the ssh link (TCP, both ways), 80x24, the TUI attached to a "
          "session on robot1")
    print(f"  {'':18}{'attach robot1:NAME':>20}{'ssh -t ... attach':>20}{'fewer':>7}"
          f"{'ssh -C -t ...':>16}{'fewer':>7}")
    for name, ours, drawn, squeezed in rows:
        label = {"demo": "demo, idle", "flood": "demo + 2,000 l/s",
                 "focused": "same, talker pane"}[name]
        print(f"  {label:18}{ours[1]:>16,.0f} B/s{drawn[1]:>16,.0f} B/s"
              f"{drawn[1] / max(ours[1], 1):>6.1f}x{squeezed[1]:>12,.0f} B/s"
              f"{squeezed[1] / max(ours[1], 1):>6.1f}x")
    print("time to attach (command start to the first node line on screen)")
    for name, ours, drawn, squeezed in rows:
        print(f"  {name:18}{ours[0]:>18.2f} s{drawn[0]:>18.2f} s{squeezed[0]:>18.2f} s")
    print(json.dumps({name: {"ours": ours, "drawn": drawn, "drawn_compressed": squeezed}
                      for name, ours, drawn, squeezed in rows}))


if __name__ == "__main__":
    if sys.argv[1:2] == ["__relay"]:
        relay(sys.argv[2], int(sys.argv[3]), sys.argv[4])
    else:
        main()
