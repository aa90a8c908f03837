"""Plot figures (issue 40), one run on this machine.

A session runs two publishers of geometry_msgs/Point (3 numeric fields: tests/integration/nodes/
signal_node.py), one at 1 kHz and one at 100 Hz. For each topic, over MEASURE_S seconds:

- the session server's CPU (its process, the publishers excluded) with nobody plotting,
  then while `tuilaunch plot NAME TOPIC x y z` shows the plot full screen at 80x24 in a
  terminal of its own (a pty read by this script), and the plot client's own CPU;
- the bytes a second the plot costs on the session's link (the `plot` events, what an ssh
  link between the TUI and the session carries), and the bytes a second the plot screen
  writes to its terminal (what `ssh -t` would carry to draw it), and the same deflated with
  zlib level 6 flushed at each write (an estimate of `ssh -C -t`: ssh's compression is zlib);
- `tuilaunch plot --csv` (every message) in the same way, its output to /dev/null;
- beside them a plain rclpy subscriber printing each message's fields (the stand-in for
  `ros2 topic echo`, whose ros2cli is not installable here: it deserializes each message in
  an executor callback and prints it), its output to /dev/null;
- then (issue 47) 4 fields of 2 topics at 1 kHz on one plot (`tuilaunch plot NAME
  /bench/fast x y /bench/fast2 x y`, a second 1 kHz publisher): the server's and the plot
  client's CPU, full screen and with --csv.

    python bench/plot_bench.py            # all of it
    python bench/plot_bench.py two        # the 4 fields of 2 topics only
"""

from __future__ import annotations

import fcntl
import json
import os
import pty
import struct
import subprocess
import sys
import tempfile
import termios
import textwrap
import threading
import time
import zlib
from pathlib import Path

from tuilaunch.client.link import Link

sys.path.insert(0, str(Path(__file__).parent))
from inspector_bench import cpu_ticks, tl  # the session commands, /proc ticks

MEASURE_S = 10.0
ROOT = Path(__file__).resolve().parent.parent
SIGNAL_NODE = ROOT / "tests" / "integration" / "nodes" / "signal_node.py"
LAUNCH = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='fast', cmd=[{python!r}, {node!r}, 'bench_fast', '--topic',
                                         '/bench/fast', '--rate', '1000']),
        ExecuteProcess(name='slow', cmd=[{python!r}, {node!r}, 'bench_slow', '--topic',
                                         '/bench/slow', '--rate', '100']),
        ExecuteProcess(name='fast2', cmd=[{python!r}, {node!r}, 'bench_fast2', '--topic',
                                          '/bench/fast2', '--rate', '1000']),
    ])
"""
ECHO_STANDIN = textwrap.dedent("""
    import sys, rclpy
    from geometry_msgs.msg import Point
    from rclpy.qos import qos_profile_sensor_data
    rclpy.init()
    node = rclpy.create_node('bench_echo')
    def show(m):
        print(f"x: {m.x}\\ny: {m.y}\\nz: {m.z}\\n---", flush=True)
    node.create_subscription(Point, sys.argv[1], show, 10)
    rclpy.spin(node)
""")


def cpu_over(pids: list[int], seconds: float) -> list[float]:
    """% of one core each process used over the next `seconds`."""
    before = [cpu_ticks(p) for p in pids]
    started = time.monotonic()
    time.sleep(seconds)
    elapsed = time.monotonic() - started
    return [100 * (cpu_ticks(p) - b) / os.sysconf("SC_CLK_TCK") / elapsed
            for p, b in zip(pids, before, strict=True)]


class LinkBytes:
    """A second client doing what the plot client does: the bytes its events cost."""

    def __init__(self, name: str, topic: str, raw: bool) -> None:
        self.link = Link(name, timeout=60)
        self.link.request("subscribe", max_lines=1, kinds=["plot"])
        self.link.request("plot", topic=topic, fields=["x", "y", "z"], raw=raw, tag=1)
        self.bytes = 0
        self.deflated = 0
        self.zip = zlib.compressobj(6)  # as ssh -o Compression=yes, each message flushed
        self.stop = False
        self.thread = threading.Thread(target=self.read, daemon=True)
        self.thread.start()

    def read(self) -> None:
        while not self.stop:
            try:
                message = self.link.receive_until(time.monotonic() + 0.5)
            except TimeoutError:
                continue
            if message is None:
                return
            line = json.dumps(message, separators=(",", ":")).encode() + b"\n"
            self.bytes += len(line)
            self.deflated += len(self.zip.compress(line) + self.zip.flush(zlib.Z_SYNC_FLUSH))

    def close(self) -> None:
        self.stop = True
        self.thread.join(5)
        self.link.close()


def link_bytes(name: str, topic: str, raw: bool) -> tuple[float, float]:
    """Bytes a second of the `plot` events of x y z, as a client of its own receives them,
    and deflated as the ssh link (Compression=yes) carries them."""
    wire = LinkBytes(name, topic, raw)
    time.sleep(3)
    wire.bytes = wire.deflated = 0
    time.sleep(MEASURE_S / 2)
    rates = wire.bytes / (MEASURE_S / 2), wire.deflated / (MEASURE_S / 2)
    wire.close()
    return rates


class PtyClient:
    """`tuilaunch plot ...` on a pty of 80x24 whose output this script reads and counts."""

    def __init__(self, *args: str) -> None:
        master, slave = pty.openpty()
        fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 80, 0, 0))
        self.proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", "plot", *args],
                                     stdin=slave, stdout=slave, stderr=slave,
                                     env={**os.environ, "TERM": "xterm-256color"},
                                     start_new_session=True)
        os.close(slave)
        self.master = master
        self.bytes = 0
        self.deflated = 0
        self.counting = False
        self.zip = zlib.compressobj(6)
        threading.Thread(target=self.read, daemon=True).start()

    def read(self) -> None:
        while True:
            try:
                data = os.read(self.master, 65536)
            except OSError:
                return
            if not data:
                return
            if self.counting:
                self.bytes += len(data)
                self.deflated += len(self.zip.compress(data) +
                                     self.zip.flush(zlib.Z_SYNC_FLUSH))

    def close(self) -> None:
        os.write(self.master, b"q")
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        os.close(self.master)


def main() -> None:
    os.environ.setdefault("ROS_DOMAIN_ID", str(100 + os.getpid() % 100))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    folder = Path(tempfile.mkdtemp(prefix="tlp"))
    os.environ["XDG_RUNTIME_DIR"] = str(folder)
    os.environ["ROS_LOG_DIR"] = str(folder / "log")
    launch = folder / "plot_bench.launch.py"
    launch.write_text(LAUNCH.format(python=sys.executable, node=str(SIGNAL_NODE)))
    name = tl(str(launch), "--detach", "--name", "plotbench").strip()
    try:
        for process in ("fast-1", "slow-2", "fast2-3"):
            tl("wait", name, process, "running", "--timeout", "60")
        server = int(json.loads(tl("status", name, "--json"))["pid"])
        tl("topics", name)  # the server's ROS node is up from here
        time.sleep(2)
        (idle,) = cpu_over([server], MEASURE_S)
        print(f"session server, nobody plotting: {idle:5.1f}% of a core")
        if sys.argv[1:] == ["two"]:
            two_topics(name, server)
            return
        for topic, rate in (("/bench/fast", 1000), ("/bench/slow", 100)):
            print(f"{topic} ({rate} Hz, geometry_msgs/Point, plotting x y z), "
                  f"{MEASURE_S:g} s each:")
            plot = PtyClient(name, topic, "x", "y", "z")
            time.sleep(4)  # discovery, the first points drawn
            plot.counting = True
            server_cpu, client_cpu = cpu_over([server, plot.proc.pid], MEASURE_S)
            screen, deflated = plot.bytes / MEASURE_S, plot.deflated / MEASURE_S
            plot.close()
            link_rate, link_deflated = link_bytes(name, topic, raw=False)
            print(f"   plot on screen:  server {server_cpu:5.1f}%, plot client "
                  f"{client_cpu:5.1f}% of a core; session link {link_rate:6.0f} B/s "
                  f"({link_deflated:5.0f} B/s deflated); its terminal {screen:6.0f} B/s "
                  f"({deflated:5.0f} B/s deflated)")
            with open(os.devnull, "w") as null:
                csv = subprocess.Popen([sys.executable, "-m", "tuilaunch", "plot", name, topic,
                                        "x", "y", "z", "--csv"], stdout=null)
                time.sleep(4)
                server_cpu, client_cpu = cpu_over([server, csv.pid], MEASURE_S)
                csv.terminate()
                csv.wait(10)
                link_rate, link_deflated = link_bytes(name, topic, raw=True)
                print(f"   --csv:           server {server_cpu:5.1f}%, csv client "
                      f"{client_cpu:5.1f}% of a core; session link {link_rate:6.0f} B/s "
                      f"({link_deflated:5.0f} B/s deflated)")
                echo = subprocess.Popen([sys.executable, "-c", ECHO_STANDIN, topic],
                                        stdout=null)
                time.sleep(4)
                (echo_cpu,) = cpu_over([echo.pid], MEASURE_S)
                echo.kill()
                echo.wait()
            print(f"   echo stand-in (rclpy subscriber printing each message): "
                  f"{echo_cpu:5.1f}% of a core")
        two_topics(name, server)
    finally:
        tl("stop", name)


def two_topics(name: str, server: int) -> None:
    """4 fields of 2 topics at 1 kHz on one plot: full screen, then --csv."""
    words = ["/bench/fast", "x", "y", "/bench/fast2", "x", "y"]
    print(f"4 fields of 2 topics at 1 kHz ({' '.join(words)}), {MEASURE_S:g} s each:")
    plot = PtyClient(name, *words)
    time.sleep(4)
    plot.counting = True
    server_cpu, client_cpu = cpu_over([server, plot.proc.pid], MEASURE_S)
    screen = plot.bytes / MEASURE_S
    plot.close()
    print(f"   plot on screen:  server {server_cpu:5.1f}%, plot client {client_cpu:5.1f}% "
          f"of a core; its terminal {screen:6.0f} B/s")
    with open(os.devnull, "w") as null:
        csv = subprocess.Popen([sys.executable, "-m", "tuilaunch", "plot", name, *words,
                                "--csv"], stdout=null)
        time.sleep(4)
        server_cpu, client_cpu = cpu_over([server, csv.pid], MEASURE_S)
        csv.terminate()
        csv.wait(10)
    print(f"   --csv:           server {server_cpu:5.1f}%, csv client {client_cpu:5.1f}% "
          "of a core")


if __name__ == "__main__":
    main()
