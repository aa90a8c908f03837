"""Inspector figures, one run on this machine.

1. Rate accuracy against publishers with known rates (1 Hz and 100 Hz timers; target:
   within 5%), measured as `tuilaunch hz` measures them (RosBridge.start_rates, 10 s window).
2. The inspector's own CPU (this process, % of one core as top shows it) while it measures
   a 1 kHz topic, beside the same bridge measuring nothing, and beside a stand-in for
   `ros2 topic hz` (ros2cli is not installed here: HZ_STANDIN does what ros2topic's hz.py
   does, a raw subscription whose callback records receive times, spun by rclpy) measuring
   the same topic in its own process. The 1 kHz publisher publishes from a plain loop rather
   than an executor's timer (rclpy's timers cost more Python than a publish), catching up in
   bursts when the machine is busy; the rate it actually published over each measurement is
   printed beside the rate read. "Subscribed, taking nothing" is the floor under both: DDS
   receiving the messages in this process before any Python runs.

3. The session server's own CPU (its process, the launch's nodes excluded) with no client,
   then while one client watches a 100 Hz topic's rate and every process's resources (the
   `watch_rates` and `watch_resources` requests the topics tab and the tree send), and the
   bytes a second those events cost on its socket.

(The wire cost of the topics tab at 80x24 is the TUI's figure, in bench/tui_bench.py.)

    python bench/inspector_bench.py
"""

from __future__ import annotations

import asyncio
import json
import os
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from pathlib import Path

from tuilaunch.client.link import Link
from tuilaunch.engine.ros.bridge import RosBridge
from tuilaunch.engine.run.session.resources import ResourceSampler

PUBLISHER = textwrap.dedent("""
    import sys, rclpy
    from std_msgs.msg import String
    rclpy.init()
    node = rclpy.create_node('bench_pub_' + sys.argv[2])
    pub = node.create_publisher(String, sys.argv[2], 10)
    node.create_timer(1.0 / float(sys.argv[1]), lambda: pub.publish(String(data='x' * 64)))
    print('ready', flush=True)
    rclpy.spin(node)
""")
FAST_PUBLISHER = textwrap.dedent("""
    import sys, time, rclpy
    from std_msgs.msg import String
    rclpy.init()
    rate, topic = float(sys.argv[1]), sys.argv[2]
    node = rclpy.create_node('bench_pub_' + topic)
    pub = node.create_publisher(String, topic, 10)
    message = String(data='x' * 64)
    print('ready', flush=True)
    period, count = 1.0 / rate, 0
    due = reported = time.monotonic()
    while True:
        now = time.monotonic()
        if now < due:
            time.sleep(due - now)
        pub.publish(message)
        count += 1
        due = max(due + period, now - 0.1)  # behind: catch up in bursts, at most 0.1 s
        if now - reported >= 0.25:
            print(now, count, flush=True)
            reported = now
""")
HZ_STANDIN = textwrap.dedent("""
    import sys, threading, rclpy
    from rclpy.qos import qos_profile_sensor_data
    from std_msgs.msg import String
    rclpy.init()
    node = rclpy.create_node('bench_hz')
    clock, lock, times, last = node.get_clock(), threading.Lock(), [], [-1]

    def received(data):  # as ROSTopicHz.callback_hz: periods between receive times
        with lock:
            now = clock.now().nanoseconds
            if last[0] >= 0:
                times.append(now - last[0])
                if len(times) > 10000:
                    times.pop(0)
            last[0] = now

    node.create_subscription(String, sys.argv[1], received, qos_profile_sensor_data,
                             raw=True)
    print('ready', flush=True)
    printed = clock.now().nanoseconds
    while rclpy.ok():  # as _rostopic_hz: spin once, print the mean rate once a second
        rclpy.spin_once(node)
        with lock:
            if times and last[0] - printed >= 1e9:
                print(1e9 * len(times) / sum(times), len(times), flush=True)
                printed = last[0]
""")
WINDOW_S = 10.0


def publisher(rate: float, topic: str) -> subprocess.Popen[str]:
    proc = subprocess.Popen([sys.executable, "-c", PUBLISHER, str(rate), topic],
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "ready"
    return proc


class Lines:
    """A child's stdout lines as they come, read in a thread (the child prints figures)."""

    def __init__(self, proc: subprocess.Popen[str]) -> None:
        self.lines: list[tuple[float, ...]] = []
        self.thread = threading.Thread(target=self.read, args=(proc,), daemon=True)
        self.thread.start()

    def read(self, proc: subprocess.Popen[str]) -> None:
        assert proc.stdout is not None
        for line in proc.stdout:
            self.lines.append(tuple(float(f) for f in line.split()))


def fast_publisher(rate: float, topic: str) -> tuple[subprocess.Popen[str], Lines]:
    """The publisher and its `(time, messages published so far)` lines."""
    proc = subprocess.Popen([sys.executable, "-c", FAST_PUBLISHER, str(rate), topic],
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "ready"
    return proc, Lines(proc)


def published_rate(lines: Lines, start: float, end: float) -> float:
    """Messages a second the publisher published between its reports nearest these times."""
    inside = [(t, n) for t, n in lines.lines if start <= t <= end]
    (t0, n0), (t1, n1) = inside[0], inside[-1]
    return (n1 - n0) / (t1 - t0)


async def hz_standin_cpu(topic: str, seconds: float) -> tuple[float, float | None]:
    """% of one core the `ros2 topic hz` stand-in used over `seconds` once it receives, and
    the rate it printed last."""
    proc = subprocess.Popen([sys.executable, "-c", HZ_STANDIN, topic], stdout=subprocess.PIPE,
                            text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == "ready"
        lines = Lines(proc)
        deadline = time.monotonic() + 30
        while not lines.lines and time.monotonic() < deadline:  # matched and receiving
            await asyncio.sleep(0.1)
        before, started = cpu_ticks(proc.pid), time.monotonic()
        await asyncio.sleep(seconds)
        used = (cpu_ticks(proc.pid) - before) / os.sysconf("SC_CLK_TCK")
        rate = lines.lines[-1][0] if lines.lines else None
        return 100 * used / (time.monotonic() - started), rate
    finally:
        proc.kill()
        proc.wait(timeout=30)


async def dds_floor(bridge: RosBridge, topic: str, seconds: float) -> float:
    """This process's CPU while a subscription no one takes from receives the topic: what
    DDS costs before any Python runs (a node of the bridge's context no executor spins)."""
    import rclpy
    from std_msgs.msg import String

    node = rclpy.create_node("bench_floor", context=bridge.node.context)
    try:
        node.create_subscription(String, topic, lambda _data: None, 10, raw=True)
        await asyncio.sleep(1)
        return await own_cpu(seconds)
    finally:
        node.destroy_node()


async def own_cpu(seconds: float) -> float:
    sampler = ResourceSampler()
    sampler.sample({"self": os.getpid()})
    await asyncio.sleep(seconds)
    return sampler.sample({"self": os.getpid()})["self"].cpu_percent or 0.0


SESSION_LAUNCH = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='pub', cmd=[{python!r}, '-c', {code!r},
                                                              '100', 'bench_session'])])
"""


def tl(*args: str) -> str:
    done = subprocess.run([sys.executable, "-m", "tuilaunch", *args], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return done.stdout


def cpu_ticks(pid: int) -> int:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return int(fields[11]) + int(fields[12])


def server_cpu(pid: int, seconds: float, link: Link | None = None) -> tuple[float, float]:
    """% of one core the server used over `seconds`, and the bytes/s `link` received."""
    received = 0
    before, started = cpu_ticks(pid), time.monotonic()
    while (left := started + seconds - time.monotonic()) > 0:
        if link is None:
            time.sleep(left)
            continue
        link.sock.settimeout(left)
        try:
            message = link.receive()
        except TimeoutError:
            break
        received += len(json.dumps(message, separators=(",", ":"))) + 1
    elapsed = time.monotonic() - started
    used = (cpu_ticks(pid) - before) / os.sysconf("SC_CLK_TCK")
    return 100 * used / elapsed, received / elapsed


def session_cost() -> None:
    print("3. the session server while a client watches rates and resources")
    folder = Path(tempfile.mkdtemp(prefix="tlb"))
    os.environ["XDG_RUNTIME_DIR"] = str(folder)
    os.environ["ROS_LOG_DIR"] = str(folder / "log")
    launch = folder / "bench_session.launch.py"
    launch.write_text(SESSION_LAUNCH.format(python=sys.executable, code=PUBLISHER))
    name = tl(str(launch), "--detach", "--name", "bench").strip()
    try:
        tl("wait", name, "pub-1", "running", "--timeout", "60")
        pid = int(json.loads(tl("status", name, "--json"))["pid"])
        link = Link(name, timeout=60)
        link.request("subscribe", max_lines=1, kinds=["rates", "resources"])
        link.request("watch_rates", topics=["/bench_session"])  # the bridge is up from here
        link.request("watch_rates", topics=[])
        idle, _ = server_cpu(pid, 5)
        link.request("watch_rates", topics=["/bench_session"])
        link.request("watch_resources", on=True)
        watched, wire = server_cpu(pid, 10, link)
        link.close()
        print(f"   no client watching:                        {idle:5.1f}% of a core")
        print(f"   watching a 100 Hz topic's rate + resources: {watched:5.1f}% of a core, "
              f"{wire:.0f} B/s on the wire")
    finally:
        tl("stop", name)


async def main() -> None:
    os.environ.setdefault("ROS_DOMAIN_ID", str(100 + os.getpid() % 100))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    procs = [publisher(1, "bench_1hz"), publisher(100, "bench_100hz")]
    bridge = RosBridge("tuilaunch_bench")
    try:
        print("1. rate accuracy (10 s window)")
        topics = ["/bench_1hz", "/bench_100hz"]
        await bridge.start_rates(topics, window_s=WINDOW_S, wait=30)
        await asyncio.sleep(WINDOW_S + 1)
        results = await bridge.read_rates()
        for topic, nominal in zip(topics, (1.0, 100.0), strict=True):
            rate = results[topic]["rate_hz"] or 0.0
            error = 100 * (rate - nominal) / nominal
            print(f"   {topic:14} nominal {nominal:6.1f} Hz  measured {rate:8.3f} Hz  "
                  f"error {error:+5.1f}%  ({results[topic]['messages']} messages, "
                  f"{results[topic]['bytes_per_s']} B/s)")
        await bridge.stop_rates()
        print("2. CPU while measuring a 1 kHz topic (5 s each)")
        idle = await own_cpu(5)
        fast, reports = fast_publisher(1000, "bench_1khz")
        procs.append(fast)
        floor = await dds_floor(bridge, "/bench_1khz", 5)
        await bridge.start_rates(["/bench_1khz"], window_s=WINDOW_S, wait=30)
        await asyncio.sleep(1)
        started = time.monotonic()
        measuring = await own_cpu(5)
        ended = time.monotonic()
        rate = (await bridge.read_rates("/bench_1khz"))["/bench_1khz"]["rate_hz"]
        await bridge.stop_rates()
        sent = published_rate(reports, started, ended)
        started = time.monotonic()
        standin, standin_rate = await hz_standin_cpu("/bench_1khz", 5)
        standin_sent = published_rate(reports, started, time.monotonic())
        print(f"   bridge measuring nothing:          {idle:5.1f}% of a core")
        print(f"   subscribed, taking nothing:        {floor:5.1f}% of a core "
              "(DDS receiving the messages: the floor)")
        print(f"   bridge measuring the 1 kHz topic:  {measuring:5.1f}% of a core, "
              f"read {rate} Hz (published {sent:.1f} Hz)")
        print(f"   `ros2 topic hz` stand-in, alone:   {standin:5.1f}% of a core, "
              f"read {standin_rate or 0:.3f} Hz (published {standin_sent:.1f} Hz)")
    finally:
        bridge.close()
        for proc in procs:
            proc.kill()
            proc.wait(timeout=30)


if __name__ == "__main__":
    asyncio.run(main())
    session_cost()
