"""Plots of several topics on a real session of known signals: a geometry_msgs/Point wave
without header (nodes/signal_node.py) and sensor_msgs/JointState stamped far from the
clock, whose positions are of magnitudes 1 and 1e5 (nodes/joints_node.py). `--csv` of both
has a column per field and a row per message, every value as published; `--stamp` times
are the stamps; the plot screen in a terminal (tmux, 80x24) stacks the magnitudes in
panels, switches to the stamps with `t`, saves what it holds with `S` (checked value by
value), draws XY with `x`, and its picker marks [X] and lists every joint.

One session serves the module.
"""

from __future__ import annotations

import csv
import io
import os
import shutil
import subprocess
import sys
import textwrap
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from ..conftest import run_cli, session_folders
from .launch_world import make_package
from .nodes.joints_node import ORIGIN, positions
from .nodes.signal_node import expected
from .session_steps import start_here, stop_here
from .test_sessions import wait_state

NODES = Path(__file__).resolve().parent / "nodes"
WRAPPER = f"""#!{sys.executable}
import runpy, sys
script = sys.argv.pop(1)  # the node's own arguments follow
runpy.run_path({str(NODES)!r} + "/" + script + ".py", run_name="__main__")
"""
LAUNCH = """
from launch import LaunchDescription
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        Node(package='several_nodes', executable='run', name='wave',
             arguments=['signal_node', 'wave', '--topic', '/sev/wave', '--rate', '50']),
        Node(package='several_nodes', executable='run', name='joints',
             arguments=['joints_node', 'joints', '--topic', '/sev/joints', '--rate', '50']),
    ])
"""
WAVE, JOINTS = "/sev/wave", "/sev/joints"
RATE = 50.0


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    root = tmp_path_factory.mktemp("several")
    prefix = root / "prefix"
    make_package(prefix, "several_nodes", ["run"], probe=WRAPPER)
    (root / "several.launch.py").write_text(textwrap.dedent(LAUNCH))
    with session_folders(root / "log", prefix):
        # the module's setting, started and ended from this process: the commands tested
        # are the ones the tests run on it
        name = start_here(root / "several.launch.py", "--name", "sev")
        try:
            for process in ("wave-1", "joints-2"):
                wait_state(name, process, "running")
            yield name
        finally:
            stop_here(name)


def table(text: str) -> tuple[list[str], list[dict[str, str]]]:
    reader = csv.DictReader(io.StringIO(text))
    rows = list(reader)
    return list(reader.fieldnames or []), rows


def consecutive(numbers: list[int]) -> bool:
    return numbers == list(range(numbers[0], numbers[0] + len(numbers)))


def test_csv_of_two_topics_has_a_column_per_field_and_a_row_per_message(session):
    done = run_cli("plot", session, WAVE, "x", "z", JOINTS, "position[0]", "position[1]",
                   "position[2]", "--csv", "--duration", "3")
    assert done.returncode == 0, done.stderr
    header, rows = table(done.stdout)
    assert header == ["time", f"{WAVE}/x", f"{WAVE}/z", f"{JOINTS}/position[0]",
                      f"{JOINTS}/position[1]", f"{JOINTS}/position[2]"]
    waves = [r for r in rows if r[f"{WAVE}/z"]]
    joints = [r for r in rows if r[f"{JOINTS}/position[2]"]]
    assert len(waves) > 20 and len(joints) > 20
    assert len(waves) + len(joints) == len(rows)  # a row is one message of one topic
    assert all(not r[f"{JOINTS}/position[0]"] for r in waves)
    assert all(not r[f"{WAVE}/x"] for r in joints)
    samples = [int(float(r[f"{WAVE}/z"])) for r in waves]
    assert consecutive(samples)
    for row, k in zip(waves, samples, strict=True):
        assert float(row[f"{WAVE}/x"]) == expected(k, RATE, 4.0)[0]
    counts = [int(float(r[f"{JOINTS}/position[2]"])) for r in joints]
    assert consecutive(counts)
    for row, k in zip(joints, counts, strict=True):  # magnitudes 1 and 1e5, both exact
        assert [float(row[f"{JOINTS}/position[{i}]"]) for i in range(3)] == positions(k, RATE)
    times = [float(r["time"]) for r in rows]
    assert times[0] == 0.0 and times == sorted(times)


def test_stamp_makes_the_time_each_message_header_stamp_in_epoch_seconds(session):
    done = run_cli("plot", session, JOINTS, "position[1]", "position[2]", "--csv",
                   "--duration", "2", "--stamp")
    assert done.returncode == 0, done.stderr
    header, rows = table(done.stdout)
    assert header == ["time", f"{JOINTS}/position[1]", f"{JOINTS}/position[2]"]
    assert len(rows) > 20
    for row in rows:
        k = int(float(row[f"{JOINTS}/position[2]"]))
        # the stamp, not the clock (1970-01-12, where the clock says today)
        assert row["time"] == f"{ORIGIN + k / RATE:.6f}"
        assert float(row[f"{JOINTS}/position[1]"]) == positions(k, RATE)[1]


@pytest.mark.parametrize("words, said", [
    ([WAVE, "x", JOINTS], f"{JOINTS} has no field to plot"),
    ([WAVE, "x", JOINTS, "nope"], f"{JOINTS} (sensor_msgs/msg/JointState) has no numeric "
     "field 'nope'"),
])
def test_a_topic_without_a_field_or_with_a_wrong_one_is_one_line(session, words, said):
    done = run_cli("plot", session, *words, "--csv", "--duration", "1")
    assert done.returncode == 2 and done.stdout == ""
    line, = done.stderr.strip().splitlines()
    assert line.startswith("tuilaunch plot: error: ") and said in line, line


# --- on screen -------------------------------------------------------------------------------

SOCKET = f"tuilaunch-plots-{uuid.uuid4().hex[:8]}"


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", "-L", SOCKET, *args], capture_output=True, text=True,
                          check=False).stdout


def screen_until(check: Callable[[str], bool], what: str, limit: float = 90) -> str:
    deadline = time.monotonic() + limit
    screen = ""
    while time.monotonic() < deadline:
        screen = tmux("capture-pane", "-p", "-t", "plot")
        if check(screen):
            return screen
        time.sleep(0.3)
    raise AssertionError(f"never {what}:\n{screen}")


@pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")
def test_the_plot_screen_of_two_topics_panels_stamps_saves_xy_and_picks(session, tmp_path):
    status_file = tmp_path / "status"
    command = (f"cd {tmp_path} && {sys.executable} -m tuilaunch plot {session} {WAVE} x "
               f"{JOINTS} 'position[0]' 'position[1]'; echo $? > {status_file}")
    tmux_env = [f"{k}={os.environ[k]}" for k in (
        "XDG_RUNTIME_DIR", "ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOG_DIR",
        "AMENT_PREFIX_PATH", "PATH") if k in os.environ]
    tmux("new-session", "-d", "-s", "plot", "-x", "80", "-y", "24", "env", *tmux_env,
         "sh", "-c", command)
    try:
        # magnitudes 1 and 1e5 apart: two panels (two frames), each readable
        screen = screen_until(lambda s: s.count("┌") >= 2 and "100000.0┤" in s and
                              "max  1e+05" in s, "two panels")
        lines = screen.splitlines()
        assert lines[0].split() == ["2", "topics", "10", "s", "(w)", "arrival", "(t)",
                                    "live"], screen
        assert f"■ {WAVE}/x" in screen and "…/joints/position[1]" in screen
        assert all(len(line) <= 80 for line in lines) and len(lines) <= 24

        tmux("send-keys", "-t", "plot", "y")  # one axis: the small one flattened
        screen_until(lambda s: "one axis" in s.splitlines()[0] and s.count("┌") == 1,
                     "one axis")
        tmux("send-keys", "-t", "plot", "y", "y")  # a panel each, then automatic again

        tmux("send-keys", "-t", "plot", "t")  # by header.stamp: the wave has none
        screen_until(lambda s: "header.stamp (t)" in s.splitlines()[0] and
                     "no header.stamp" in s and "max  1e+05" in s, "the stamps")
        time.sleep(1.0)  # a few points more than the kept ones
        tmux("send-keys", "-t", "plot", "S")
        saved = screen_until(lambda s: "saved" in s and ".csv" in s, "saved")
        files = list(tmp_path.glob("plot-*.csv"))
        assert len(files) == 1, saved
        header, rows = table(files[0].read_text())
        first = f"{JOINTS}/position[0]"
        assert header[:4] == ["time", f"{WAVE}/x", f"{WAVE}/x min", f"{WAVE}/x max"]
        assert header[4:] == [first, f"{first} min", f"{first} max",
                              f"{JOINTS}/position[1]", f"{JOINTS}/position[1] min",
                              f"{JOINTS}/position[1] max"]
        joints = [r for r in rows if r[first]]
        assert len(joints) > 20
        for row in joints:
            # a point's time is its last message's stamp: which sample it was
            k = round((float(row["time"]) - ORIGIN) * RATE)
            assert float(row["time"]) == pytest.approx(ORIGIN + k / RATE, abs=1e-6)
            want = [float(f"{v:.6g}") for v in positions(k, RATE)[:2]]  # as sent: 6 digits
            assert [float(row[first]), float(row[f"{JOINTS}/position[1]"])] == want, row
            assert float(row[f"{first} min"]) <= want[0] <= float(row[f"{first} max"])

        tmux("send-keys", "-t", "plot", "x")  # the first field on the axis against the second
        screen_until(lambda s: "XY" in s.splitlines()[0], "XY")
        tmux("send-keys", "-t", "plot", "x", "f")
        picker = screen_until(lambda s: "[ ] /sev/joints/position[2]" in s, "the picker")
        assert f"[X] {WAVE}/x" in picker and "[X] /sev/joints/position[0]" in picker
        assert f"[ ] {WAVE}/y" in picker
        tmux("send-keys", "-t", "plot", "Escape")
        screen_until(lambda s: "[X]" not in s, "the picker closed")
        tmux("send-keys", "-t", "plot", "q")
        deadline = time.monotonic() + 30
        while not status_file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert status_file.read_text().strip() == "0"
    finally:
        tmux("kill-server")
