"""Output on a busy machine: the two ways the flood test (test_supervisor.py) lost lines
when the machine was loaded.

- Lines still waiting in a process's terminal when the launch ended were dropped: the
  reader takes one chunk per wake-up and gives up waiting for the end of a process's output
  after a second, so a loop held up by the machine closed it with lines unread. They are
  now read and logged before the channel is closed.
- Headless stdout shows no line past 1 MB waiting for a reader that is slower than the
  flood (a busy test process reading a pipe is one): those lines are counted on screen and
  are in the log; what a reader sees plus what it is told it missed is every line.
"""

from __future__ import annotations

import asyncio
import os
import re
import subprocess
import sys
import threading
import time

from tuilaunch.cli.stdout_writer import STALL, BackgroundWriter
from tuilaunch.engine import load_file, resolve
from tuilaunch.engine.run.supervisor.supervisor import Supervisor

LATE = """import os, time
time.sleep(1.5)  # its parent has exited by then: the launch is ending
os.write(1, b''.join(b'%d\\n' % i for i in range(1, 2001)))
"""


def test_output_waiting_in_a_terminal_when_the_launch_ends_is_all_logged(write, tmp_path):
    """A shell leaves a child behind that prints 2000 lines (9 KB, what a terminal holds)
    into the terminal while the supervisor's loop is held up (here by a slow consumer, on
    a busy machine by the CPU): the launch ends, and the log file has every line."""
    (tmp_path / "late.py").write_text(LATE)
    path = write(f"""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='shell', cmd=[
        'sh', '-c', '{sys.executable} {tmp_path / "late.py"} & exit 0'])])
""")
    plan = resolve(load_file(str(path)), {}, params_dir=tmp_path / "params")
    supervisor = Supervisor(plan, tmp_path / "log")

    def held_up(event) -> None:
        if event.kind == "exited":
            time.sleep(2.5)  # meanwhile the late child prints and exits

    supervisor.subscribe(held_up)
    assert asyncio.run(supervisor.run()) == 0
    logged = (tmp_path / "log" / "shell-1.log").read_text().splitlines()
    assert [line.split(" ", 2)[2] for line in logged] == [str(n) for n in range(1, 2001)]


def test_a_slow_reader_sees_every_line_or_is_told_how_many_it_was_not_shown():
    read_end, write_end = os.pipe()
    writer = BackgroundWriter(write_end, "utf-8", lambda exc: None,
                              lambda n: f"{n} output lines not shown\n", limit=64 << 10)
    line, count = "[flood-1] 123456\n", 40_000
    for n in range(count):  # nobody reads yet: the pipe fills, then the queue
        writer.write(line, 1)
        if n == count // 2:
            time.sleep(STALL * 3)  # the writer has waited on the reader: it is behind
    got: list[bytes] = []

    def read() -> None:
        while chunk := os.read(read_end, 1 << 16):
            got.append(chunk)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()  # the reader comes back
    writer.close()
    os.close(write_end)
    reader.join(30)
    os.close(read_end)
    out = b"".join(got).decode()
    skipped = sum(int(n) for n in re.findall(r"(\d+) output lines not shown", out))
    assert skipped > 0 and out.count(line) + skipped == count


def test_a_regular_file_gets_every_line_however_far_the_writer_lags(tmp_path):
    """A file never makes its writer wait: a queue past the limit is the writer thread
    short of CPU (a flood), not a slow reader, and nothing is skipped."""
    target = tmp_path / "out.txt"
    fd = os.open(target, os.O_WRONLY | os.O_CREAT, 0o600)
    writer = BackgroundWriter(fd, "utf-8", lambda exc: None,
                              lambda n: f"{n} output lines not shown\n", limit=4 << 10)
    line, count = "[flood-1] 123456\n", 40_000
    for _ in range(count):  # far faster than the thread is given the CPU to write
        writer.write(line, 1)
    writer.close()
    os.close(fd)
    assert target.read_text() == line * count


def test_a_flood_printed_headless_into_a_file_loses_no_line(write, tmp_path):
    """`tuilaunch --headless > out.txt` under a flood of four writers printed 1,979,352 of
    2,000,000 lines: into a file every line is printed."""
    count = 250_000
    path = write(f"""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(cmd=['seq', '1', '{count}'], name=f'flood{{i}}',
                                             output='screen') for i in range(4)])
""")
    out = tmp_path / "out.txt"
    with open(out, "wb") as handle:
        done = subprocess.run([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                              stdout=handle, stderr=subprocess.PIPE, timeout=300,
                              env={**os.environ, "ROS_LOG_DIR": str(tmp_path / "log")})
    assert done.returncode == 0, done.stderr
    lines = out.read_text().splitlines()
    assert not [line for line in lines if "not shown" in line]
    for i in range(4):
        prefix = f"[flood{i}-{i + 1}] "
        numbers = [line[len(prefix):] for line in lines if line.startswith(prefix)]
        assert numbers == [str(n) for n in range(1, count + 1)], prefix


def test_what_launch_code_prints_at_run_time_is_never_cut_by_the_nodes_lines(write):
    """With PYTHONUNBUFFERED (usual in ROS containers) `print(a, b, c)` writes each piece
    apart; an OpaqueFunction printing while a node floods headless stdout must still come
    out as whole lines, as under ros2 launch, where both are written by one thread."""
    from ..conftest import run_cli

    path = write(f"""
from launch import LaunchDescription
from launch.actions import ExecuteProcess, OpaqueFunction, RegisterEventHandler
from launch.event_handlers import OnProcessStart
def speak(context):
    for i in range(300):
        print('opaque', 'line', i, 'in', 'pieces', flush=True)
    return []
def generate_launch_description():
    flood = ExecuteProcess(name='flood', output='screen',
                           cmd=[{sys.executable!r}, '-c',
                                'for i in range(20000): print("flood line", i)'])
    return LaunchDescription([
        flood, RegisterEventHandler(OnProcessStart(target_action=flood,
                                                   on_start=[OpaqueFunction(function=speak)]))])
""")
    done = run_cli(str(path), "--headless", env={"PYTHONUNBUFFERED": "1"})
    assert done.returncode == 0, done.stderr
    said = [line for line in done.stdout.splitlines() if "opaque" in line]
    assert said == [f"opaque line {i} in pieces" for i in range(300)], [
        line for line in said if not re.fullmatch(r"opaque line \d+ in pieces", line)][:5]
