"""A launch pays only for what it uses: a launch of plain processes never loads rclpy (nor
starts the ROS bridge's threads) into the launcher, headless or as a session server; a
client asking for topics loads it then, and gets its answer.

Whether rclpy is loaded is read from outside, as a user could: the launcher's memory map
(`/proc/PID/maps`) lists rclpy's and rcl's shared libraries once rclpy is imported.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from .conftest import wait_for
from .inspector_helpers import NODE_SCRIPT
from .test_sessions import runtime, tl  # noqa: F401  (runtime: a fixture)

PLAIN = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription(
        [ExecuteProcess(cmd=['sleep', '600'], name=f'quiet{{i}}') for i in range(20)]
        + [ExecuteProcess(cmd=[{python!r}, {node!r}, 'light_talker', '--pub', '/light_chatter'],
                          name='talker')])
"""


def plain_launch(write) -> Path:
    """20 sleeping processes and a talker: an rclpy node of its own process, which the
    launcher only starts (it is no ROS work of the launcher's)."""
    return write(PLAIN.format(python=sys.executable, node=str(NODE_SCRIPT)))


def ros_libraries(pid: int) -> set[str]:
    """The rclpy and rcl shared libraries mapped into the process."""
    found = set()
    for line in Path(f"/proc/{pid}/maps").read_text().splitlines():
        library = line.rsplit("/", 1)[-1]
        if "/rclpy/" in line or library.startswith(("librcl", "_rclpy")):
            found.add(library)
    return found


def threads(pid: int) -> int:
    return len(os.listdir(f"/proc/{pid}/task"))


def test_a_headless_launch_of_plain_processes_loads_no_rclpy(write):
    path = plain_launch(write)
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), "--headless"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)
    try:
        assert proc.stdout is not None
        started = 0
        seen = []
        while started < 21 or not any("ready" in line for line in seen):
            line = proc.stdout.readline()
            assert line, f"tuilaunch ended early: {''.join(seen)[-2000:]}"
            seen.append(line)
            started += "process started" in line
        # every process runs and the talker is up: the launch is idle from here on
        assert ros_libraries(proc.pid) == set()
        # nor OpenSSL (asyncio's TLS, hashes): megabytes a launch of processes does not use
        maps = Path(f"/proc/{proc.pid}/maps").read_text()
        assert "libcrypto" not in maps and "libssl" not in maps
        # the event loop and the stdout writer; the ROS bridge's executor would add more
        wait_for(lambda: threads(proc.pid) <= 2, 30, "the launcher down to its 2 threads")
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        proc.communicate(timeout=120)


def server_pid(folder: Path, name: str) -> int:
    info = folder / "tuilaunch" / f"{name}.json"
    return int(json.loads(info.read_text())["pid"])


def test_a_session_loads_rclpy_only_once_a_client_asks_for_topics(runtime, write):  # noqa: F811
    name = tl(str(plain_launch(write)), "--detach", "--name", "light").stdout.strip()
    tl("wait", name, "talker-21", "running", "--timeout", "60")
    pid = server_pid(runtime, name)
    # the status, logs and waits of a session are no ROS work either
    tl("status", name)
    assert ros_libraries(pid) == set()
    assert threads(pid) <= 2

    def talker_listed() -> bool:
        listed = json.loads(tl("topics", name, "--json").stdout)["topics"]
        return any(t["name"] == "/light_chatter" and t["publishers"] for t in listed)

    deadline = time.monotonic() + 90
    while not talker_listed():  # discovery on a busy machine takes a while
        assert time.monotonic() < deadline, "the talker's topic was never listed"
        time.sleep(0.5)
    assert {lib for lib in ros_libraries(pid) if lib.startswith("librcl")}
    tl("stop", name)


@pytest.mark.parametrize("module", ["tuilaunch.cli.headless", "tuilaunch.engine.launcher",
                                    "tuilaunch.tui.app"])
def test_the_launchers_modules_import_no_rclpy(module):
    """What a plain launch imports, headless, as a session server or as the TUI's command
    line: no rclpy, no ROS message package."""
    code = (f"import sys, {module}\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & "
            "{'rclpy', 'rcl_interfaces', 'lifecycle_msgs', 'composition_interfaces'}))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


def test_asyncio_without_tls_still_runs_and_ssl_still_imports():
    """What the launcher leaves out of asyncio is only TLS: the loop runs, and a launch
    file that imports ssl itself gets it."""
    code = ("import sys\n"
            "from tuilaunch.engine.run.lean_asyncio import asyncio_without_tls\n"
            "asyncio_without_tls()\n"
            "import asyncio\n"
            "print('ssl' in sys.modules, asyncio.run(asyncio.sleep(0, 'ran')))\n"
            "import ssl\n"
            "print(ssl.create_default_context() is not None)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "ran", "True"]
