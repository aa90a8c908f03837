"""The black box's cost (issue 48), one run on this machine.

A launch of one node (tests/integration/nodes/flood_node.py) publishing 10 topics of
std_msgs/String at 100 Hz and one 640x480 rgb8 sensor_msgs/Image at 30 Hz (27.6 MB/s).
Over MEASURE_S seconds, after WARM_S (the black box full: its 10 s of images pass its
bound), this prints the session server's CPU (% of one core, its own process, the
publisher excluded) and resident memory:

- without the black box (and whether rclpy's library is loaded in it at all: it must not
  be, a launch without a recording loads no ROS bridge);
- with `--black-box 10` (the default bound, 256 MB) and with `--black-box 10
  --black-box-size 64`;
- beside them the floor: a plain rclpy subscriber of the same 11 topics (generic, raw
  bytes, an executor callback each) appending every message's bytes to a file, as a
  recorder that only writes must (`ros2 bag record` is not installable here).

    python bench/record_bench.py
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from inspector_bench import cpu_ticks, tl  # the session commands, /proc ticks

WARM_S, MEASURE_S = 12.0, 10.0
ROOT = Path(__file__).resolve().parent.parent
FLOOD = ROOT / "tests" / "integration" / "nodes" / "flood_node.py"
LAUNCH = """
from launch import LaunchDescription
from launch_ros.actions import Node
def generate_launch_description():
    return LaunchDescription([Node(package='bench_rec', executable='flood_node', name='flood',
        arguments=['flood', '--topics', '10', '--rate', '100', '--image-rate', '30'])])
"""
FLOOR = textwrap.dedent("""
    import sys, rclpy
    from rclpy.qos import QoSProfile
    from std_msgs.msg import String
    from sensor_msgs.msg import Image
    rclpy.init()
    node = rclpy.create_node('floor_recorder')
    out = open(sys.argv[1], 'wb')
    def keep(data):
        out.write(data)
    subs = [node.create_subscription(String, f'/flood/small_{i}', keep, QoSProfile(depth=100),
                                     raw=True) for i in range(10)]
    subs.append(node.create_subscription(Image, '/flood/image', keep, QoSProfile(depth=100),
                                         raw=True))
    print('ready', flush=True)
    try:
        rclpy.spin(node)
    except BaseException:  # terminated: the measure is over
        pass
""")


def rss_mb(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def measure(pid: int) -> tuple[float, float]:
    """% of one core over MEASURE_S, and the RSS at its end (MB)."""
    hz = os.sysconf("SC_CLK_TCK")
    before, started = cpu_ticks(pid), time.monotonic()
    time.sleep(MEASURE_S)
    used = (cpu_ticks(pid) - before) / hz / (time.monotonic() - started)
    return 100 * used, rss_mb(pid)


def prefix(folder: Path) -> Path:
    """An ament prefix with the package bench_rec and its executable flood_node."""
    root = folder / "prefix"
    (root / "share" / "ament_index" / "resource_index" / "packages").mkdir(parents=True)
    (root / "share" / "ament_index" / "resource_index" / "packages" / "bench_rec").touch()
    (root / "share" / "bench_rec").mkdir(parents=True)
    (root / "share" / "bench_rec" / "package.xml").write_text(
        "<package><name>bench_rec</name></package>\n")
    exe = root / "lib" / "bench_rec" / "flood_node"
    exe.parent.mkdir(parents=True)
    exe.write_text(f"#!{sys.executable}\n" + FLOOD.read_text())
    exe.chmod(0o755)
    return root


def session(folder: Path, name: str, *options: str) -> tuple[float, float, bool]:
    launch = folder / "flood.launch.py"
    launch.write_text(textwrap.dedent(LAUNCH))
    tl(str(launch), "--detach", "--name", name, *options)
    try:
        tl("wait", name, "flood-1", "running", "--timeout", "60")
        pid = int(json.loads(tl("status", name, "--json"))["pid"])
        time.sleep(WARM_S)
        cpu, rss = measure(pid)
        rclpy_loaded = "rclpy" in Path(f"/proc/{pid}/maps").read_text()
        return cpu, rss, rclpy_loaded
    finally:
        tl("stop", name)


def floor(folder: Path) -> tuple[float, float]:
    launch = folder / "flood.launch.py"
    launch.write_text(textwrap.dedent(LAUNCH))
    tl(str(launch), "--detach", "--name", "floor")
    script = folder / "floor.py"
    script.write_text(FLOOR)
    recorder = subprocess.Popen([sys.executable, str(script), str(folder / "floor.bin")],
                                stdout=subprocess.PIPE, text=True)
    try:
        tl("wait", "floor", "flood-1", "running", "--timeout", "60")
        assert recorder.stdout is not None and recorder.stdout.readline() == "ready\n"
        time.sleep(WARM_S)
        return measure(recorder.pid)
    finally:
        recorder.terminate()
        recorder.wait(timeout=30)
        tl("stop", "floor")
        (folder / "floor.bin").unlink(missing_ok=True)


def main() -> None:
    folder = Path(tempfile.mkdtemp(prefix="tlr"))
    os.environ["XDG_RUNTIME_DIR"] = str(folder)
    os.environ["ROS_LOG_DIR"] = str(folder / "log")
    os.environ["AMENT_PREFIX_PATH"] = os.pathsep.join(
        [str(prefix(folder)), os.environ.get("AMENT_PREFIX_PATH", "")])
    print("10 topics at 100 Hz + one 640x480 rgb8 image at 30 Hz; the server's CPU over "
          f"{MEASURE_S:g} s after {WARM_S:g} s, and its RSS")
    cpu, rss, loaded = session(folder, "off")
    print(f"  black box off             {cpu:5.1f} % of a core  {rss:6.1f} MB  "
          f"rclpy loaded: {loaded}")
    for size in ("256", "64"):
        cpu, rss, _ = session(folder, f"on{size}", "--black-box", "10",
                              "--black-box-size", size)
        print(f"  --black-box 10, {size:>3} MB   {cpu:5.1f} % of a core  {rss:6.1f} MB")
    cpu, rss = floor(folder)
    print(f"  floor: rclpy raw -> file  {cpu:5.1f} % of a core  {rss:6.1f} MB")


if __name__ == "__main__":
    main()
