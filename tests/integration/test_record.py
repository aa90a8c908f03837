"""Recordings and the black box on real sessions of real rclpy nodes, read back with the
`mcap` and `mcap-ros2-support` packages value by value (docs/recording.md).

One session serves most of the module: a 50 Hz signal (geometry_msgs/Point, z = the
sample's number) and a process that dies 12 s after its start, run with `--black-box 8`;
a second one floods 640x480 images against a small `--black-box-size`.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from tuilaunch.client.link import open_link
from tuilaunch.engine.run.vocabulary.requests import BlackBox

from ..conftest import run_cli, session_folders
from .launch_world import make_package
from .session_steps import stop_here

NODES = Path(__file__).resolve().parent / "nodes"
LAUNCH = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
from launch_ros.actions import Node
def generate_launch_description():
    return LaunchDescription([
        Node(package='rec_nodes', executable='signal_node', name='wave',
             arguments=['wave', '--topic', '/rec/wave', '--rate', '50']),
        ExecuteProcess(name='doomed', cmd=['sh', '-c',
            'echo starting; sleep 12; echo "last words before the crash"; exit 3']),
    ])
"""
FLOOD = """
from launch import LaunchDescription
from launch_ros.actions import Node
def generate_launch_description():
    return LaunchDescription([
        Node(package='rec_nodes', executable='flood_node', name='flood',
             arguments=['flood', '--image-rate', '30']),
    ])
"""
WAVE, DOOMED = "wave-1", "doomed-2"


def ok(*args: str, timeout: float = 120) -> str:
    done = run_cli(*args, timeout=timeout)
    assert done.returncode == 0, done.stderr
    return done.stdout


def eventually(check: Callable[[], Any], timeout: float = 60.0, what: str = "") -> Any:
    deadline = time.monotonic() + timeout
    while True:
        found = check()
        if found:
            return found
        assert time.monotonic() < deadline, f"waited {timeout:g} s for {what}"
        time.sleep(0.2)


def read(path: Path) -> tuple[Any, list[tuple[str, int, Any]]]:
    """The file's summary and its messages decoded: (topic, log time ns, message)."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        messages = [(channel.topic, message.log_time, decoded)
                    for _, channel, message, decoded in reader.iter_decoded_messages()]
    return summary, messages


@pytest.fixture(scope="module")
def root(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("record")
    for name in ("signal_node", "flood_node"):
        make_package(root / "prefix", "rec_nodes", [name],
                     probe=f"#!{sys.executable}\n" + (NODES / f"{name}.py").read_text())
    (root / "rec.launch.py").write_text(textwrap.dedent(LAUNCH))
    (root / "flood.launch.py").write_text(textwrap.dedent(FLOOD))
    return root


@pytest.fixture(scope="module")
def session(root: Path) -> Iterator[str]:
    with session_folders(root / "log", root / "prefix"):
        name = ok(str(root / "rec.launch.py"), "--detach", "--name", "rec",
                  "--black-box", "8").strip()
        ok("wait", name, WAVE, "running", "--timeout", "60")
        yield name
        stop_here(name)  # the setting's end, not a subject: from this process


def test_a_recording_holds_each_message_as_published_and_the_output(session, tmp_path):
    out = tmp_path / "wave.mcap"
    # the ROS environment is not needed where the file is written: only the session's
    recorder = subprocess.Popen([sys.executable, "-m", "tuilaunch", "record", session,
                                 "/rec/wave", "-o", str(out)],
                                stderr=subprocess.PIPE, text=True)
    try:
        assert recorder.stderr is not None
        first = recorder.stderr.readline()
        assert f"/rec/wave and the output into {out}" in first, first
        began = time.monotonic()
        eventually(lambda: time.monotonic() - began > 4, what="4 s of recording")
        recorder.send_signal(signal.SIGINT)  # Ctrl+C: the file is completed
        _, said = recorder.communicate(timeout=60)
    finally:
        if recorder.poll() is None:
            recorder.kill()
    assert recorder.returncode == 0, said
    assert f"{out}: " in said and "messages on 2 channels" in said
    summary, messages = read(out)
    channels = {c.topic: c for c in summary.channels.values()}
    schemas = {s.id: s for s in summary.schemas.values()}
    assert set(channels) == {"/rec/wave", "/tuilaunch/output"}
    wave = channels["/rec/wave"]
    assert wave.message_encoding == "cdr" and "offered_qos_profiles" in wave.metadata
    assert schemas[wave.schema_id].name == "geometry_msgs/msg/Point"
    assert schemas[wave.schema_id].encoding == "ros2msg"
    assert b"float64 x" in schemas[wave.schema_id].data
    points = [(t, m) for topic, t, m in messages if topic == "/rec/wave"]
    # 4 s at 50 Hz, less the subscription's discovery, which a busy machine can stretch
    # past a second (a CI run held 99 of 3 s): that every sample between the first and
    # the last is there is what says none was lost
    assert len(points) > 50
    numbers = [int(m.z) for _, m in points]
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers)))  # none lost
    from .nodes.signal_node import expected

    assert all((m.x, m.y) == expected(int(m.z), 50.0, 4.0) for _, m in points)
    times = [t for t, _ in points]
    assert times == sorted(times) and 2.5e9 < times[-1] - times[0] < 30e9
    assert summary.statistics.message_count == len(messages)


def test_the_black_box_is_written_when_a_process_dies_unasked(session):
    said = eventually(lambda: "black box written: " in (
        text := run_cli("logs", session, DOOMED).stdout) and text, timeout=90,
        what="the black box written after doomed-2's death")
    path = Path(said.split("black box written: ", 1)[1].split(" (", 1)[0])
    assert path.parent.name.startswith(tuple("0123456789")) and path.suffix == ".mcap"
    _, messages = read(path)
    points = [(t, int(m.z)) for topic, t, m in messages if topic == "/rec/wave"]
    numbers = [k for _, k in points]
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers)))
    span = (points[-1][0] - points[0][0]) / 1e9
    assert 7.0 < span <= 8.1, span  # the last 8 s, not the launch's 15
    assert 300 < len(points) <= 8 * 50 + 5
    lines = [(m.name, m.level, m.msg) for topic, _, m in messages
             if topic == "/tuilaunch/output"]
    assert (DOOMED, 20, "last words before the crash") in lines
    assert ("launch", 40, f"{DOOMED}: process has died: exit code 3") in lines
    # a file of its own for each write, never overwritten
    again = ok("record", session, "--black-box").strip()
    assert again.endswith("messages)") and str(path) not in again
    _, now = read(Path(again.split(" (", 1)[0]))
    assert any(topic == "/rec/wave" for topic, _, _ in now)


def test_a_flood_of_images_stays_within_the_black_box_size(root):
    bound = 8 << 20
    with session_folders(root / "flood-log", root / "prefix"):
        name = ok(str(root / "flood.launch.py"), "--detach", "--name", "flood",
                  "--black-box", "60", "--black-box-size", "8").strip()
        try:
            ok("wait", name, "flood-1", "running", "--timeout", "60")
            link = open_link(name, timeout=30)
            try:
                # 27 MB/s of images: the bound is reached within a second of the first
                full = eventually(lambda: (s := link.request(BlackBox()))["bytes"] >
                                  bound - 2 * 921_700 and s, what="the black box filled")
                assert full["size"] == bound
                for _ in range(10):
                    assert link.request(BlackBox())["bytes"] <= bound
                    time.sleep(0.1)
            finally:
                link.close()
            written = Path(ok("record", name, "--black-box").split(" (", 1)[0])
        finally:
            stop_here(name, gone_ok=True)
    _, messages = read(written)
    images = [m for topic, _, m in messages if topic == "/flood/image"]
    assert 3 <= len(images) <= bound // (640 * 480 * 3)
    numbers = [m.header.stamp.sec for m in images]
    assert numbers == list(range(numbers[0], numbers[0] + len(numbers)))  # the newest kept
    assert all(m.width == 640 and m.data[0] == k % 256 for m, k in zip(images, numbers,
                                                                          strict=True))
    assert written.stat().st_size < bound * 1.05
