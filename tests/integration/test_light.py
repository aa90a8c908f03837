"""A launch pays only for what it uses: a launch of plain processes never loads rclpy (nor
starts the ROS bridge's threads) into the launcher, headless or as a session server; a
client asking for topics loads it then, and gets its answer.

Whether rclpy is loaded is read from outside, as a user could: the launcher's memory map
(`/proc/PID/maps`) lists rclpy's and rcl's shared libraries once rclpy is imported.
"""

from __future__ import annotations

import asyncio
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from textual import events

from tuilaunch.cli.commands import start_session
from tuilaunch.engine.run.session import session_dir
from tuilaunch.tui.app import make_app
from tuilaunch.tui.output_store import View

from ..conftest import python_prints, wait_for
from .inspector_helpers import NODE_SCRIPT
from .session_steps import start_here, stop_here
from .test_sessions import runtime, tl, wait_state  # noqa: F401  (runtime: a fixture)
from .test_tui import until

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
    name = start_here(plain_launch(write), "--name", "light")
    wait_state(name, "talker-21", "running")
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
    stop_here(name)


@pytest.mark.parametrize("module", ["tuilaunch.cli.headless", "tuilaunch.engine.launcher",
                                    "tuilaunch.tui.app"])
def test_the_launchers_modules_import_no_rclpy(module):
    """What a plain launch imports, headless, as a session server or as the TUI's command
    line: no rclpy, no ROS message package."""
    code = (f"import sys, {module}\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & "
            "{'rclpy', 'rcl_interfaces', 'lifecycle_msgs', 'composition_interfaces'}))")
    assert python_prints(code).strip() == "[]"


def test_the_plotting_library_is_loaded_only_with_the_first_plot():
    """The TUI, the session commands and the session server run without plotext (its
    import costs time and memory a launch that plots nothing would pay)."""
    code = ("import sys, tuilaunch.tui.app, tuilaunch.cli.commands, tuilaunch.engine.launcher\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in "
            "{'plotext', 'textual_plotext', 'numpy'} or 'plot_screen' in m))")
    assert python_prints(code).strip() == "[]"


def test_only_serve_imports_its_web_server():
    """aiohttp and textual-serve (`tuilaunch serve`) are loaded by serve alone: neither the
    command line, its --help, the session commands, the launch nor the TUI loads them."""
    code = ("import contextlib, io, sys\n"
            "from tuilaunch.cli import dispatch, commands, headless\n"
            "import tuilaunch.tui.app, tuilaunch.engine.launcher\n"
            "for argv in (['--help'], ['serve', '--help'], ['ls', '--help']):\n"
            "    with contextlib.redirect_stdout(io.StringIO()), "
            "contextlib.suppress(SystemExit):\n"
            "        dispatch.main(argv)\n"
            "print(sorted({m.split('.')[0] for m in sys.modules} & "
            "{'aiohttp', 'textual_serve', 'jinja2', 'selenium'}))")
    assert python_prints(code).strip() == "[]"


def test_a_launch_on_one_machine_does_not_load_what_it_does_not_use():
    """A plain launch on this machine starts without the code of `--machines`, of
    `--print-plan --json`, of AnonName (uuid and platform), of a mistyped argument's
    suggestion or of the ROS bridge and its messages: each is imported when a launch uses
    it."""
    code = ("import sys, tuilaunch.cli.dispatch, tuilaunch.cli.headless, "
            "tuilaunch.cli.suggest, tuilaunch.engine.launcher\n"
            "print(sorted(m for m in sys.modules if m in {'json', 'uuid', 'difflib', "
            "'tempfile', 'tuilaunch.engine.plan.machines', "
            "'tuilaunch.engine.run.machines.machines_share', 'tuilaunch.engine.ros.bridge', "
            "'tuilaunch.engine.ros.calls', 'tuilaunch.engine.ros.messages'}))")
    assert python_prints(code).strip() == "[]"


def test_the_watchdog_process_starts_without_importing_anything():
    """The watchdog starts beside a launch's first processes, on the same cores: it loads
    nothing beyond os, sys and time (no subprocess, threading, nor signal's enums),
    and still does its work: the end of its pipe stops the process group it was told of."""
    from tuilaunch.engine.run.process import watchdog_process

    def imported(*argv: str, given: bytes = b"") -> set[str]:
        ran = subprocess.run([sys.executable, "-I", "-S", "-X", "importtime", *argv],
                             input=given, capture_output=True, timeout=60)
        return {line.split("|")[-1].strip() for line in ran.stderr.decode().splitlines()
                if line.startswith("import time:")}

    child = subprocess.Popen(["sleep", "600"], start_new_session=True)
    try:
        # beyond what the interpreter's own start imports
        extra = imported(watchdog_process.__file__, "test-token", "0.5",
                         given=f"+{child.pid}\n".encode()) - imported("-c", "import os, sys, time")
        assert extra <= {"_signal"}, extra
        assert child.wait(timeout=30) == -signal.SIGTERM
    finally:
        child.kill()
        child.wait()


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
    assert python_prints(code).split() == ["False", "ran", "True"]


# --- the TUI first: the tree is on screen before the first process starts -----------------

FIRST = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(cmd=['sh', '-c', 'touch "$0"; echo first up; exec sleep 600',
                            {marker!r}], name='first'),
        ExecuteProcess(cmd=['sleep', '600'], name='second')])
"""


def tui_launch(write, tmp_path: Path) -> tuple[Path, Path]:
    marker = tmp_path / "first-started"
    return write(FIRST.format(marker=str(marker))), marker


def test_the_tree_is_drawn_before_the_first_process_starts(runtime, write, tmp_path):  # noqa: F811
    """As `tuilaunch FILE` in a terminal: the app draws the plan's tree, every process
    waiting; only once that frame is out does the session's server, and so the launch,
    start; then the same tree follows the processes."""
    path, marker = tui_launch(write, tmp_path)
    log_dir = tmp_path / "log"
    order: list[str] = []
    seen_at_start: dict[str, object] = {}

    def start_server() -> subprocess.Popen[bytes]:
        # what the user has on screen at the instant the launch is started
        seen_at_start["marker"] = marker.exists()
        seen_at_start["rows"] = {process: str(row.label)
                                 for process, row in app.launch_tree.rows.items()}
        order.append("launch started")
        return start_session(str(path), {}, "first", log_dir)[1]

    def hook(message: object) -> None:
        if isinstance(message, events.Ready):  # posted once the first frame is displayed
            order.append("first frame")

    app = make_app(str(path), {}, log_dir, session_name="first", owner=True,
                   start_server=start_server)

    async def scenario() -> None:
        async with app.run_test(size=(100, 30), message_hook=hook) as pilot:
            await until(pilot, lambda: app.supervisor is not None and
                        app.supervisor.states.get("first-1") == "running")
            assert "running" in str(app.launch_tree.rows["first-1"].label)
            await until(pilot, lambda: any("first up" in line.text
                                           for line in app.store.lines(View("first-1"))))
            await pilot.press("q")
            await pilot.press("y")
            await until(pilot, lambda: not app.is_running)

    asyncio.run(scenario())
    assert order == ["first frame", "launch started"]
    assert seen_at_start["marker"] is False  # no process of the launch had started
    rows = seen_at_start["rows"]
    assert isinstance(rows, dict) and set(rows) == {"first-1", "second-2"}
    assert all("waiting" in label for label in rows.values())
    assert marker.exists()  # and then it did start
    server = app.server_process
    assert server is not None
    assert server.wait(timeout=60) == 0


def test_quitting_while_the_launch_starts_leaves_nothing_running(runtime, write, tmp_path):  # noqa: F811
    """q in the instant between the first frame and the server's answer: the app leaves,
    and the server it was starting stops with every process it had started."""
    path, _marker = tui_launch(write, tmp_path)
    log_dir = tmp_path / "log"
    gate = threading.Event()

    def start_server() -> subprocess.Popen[bytes]:
        gate.wait(60)  # held until the app has quit
        return start_session(str(path), {}, "quitter", log_dir)[1]

    app = make_app(str(path), {}, log_dir, session_name="quitter", owner=True,
                   start_server=start_server)

    async def scenario() -> None:
        async with app.run_test(size=(100, 30)) as pilot:
            await pilot.press("q")
            await until(pilot, lambda: not app.is_running)

    asyncio.run(scenario())
    gate.set()
    wait_for(lambda: app.server_process is not None, 60, "the server started")
    server = app.server_process
    assert server is not None
    # told to stop as soon as it was up: a server ends once every process it started has
    server.wait(timeout=60)
    assert not session_dir.is_alive("quitter")
