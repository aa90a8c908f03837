"""Shared helpers: load and resolve launch files written by a test, run the CLI."""

from __future__ import annotations

import json
import os
import queue
import signal
import subprocess
import sys
import tempfile
import textwrap
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from tuilaunch.engine import Plan, load_file, resolve
from tuilaunch.engine.packages import ensure_environment, known_packages

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"

ensure_environment()

# Every test run gets its own DDS domain, and discovery stays on this machine, so parallel
# runs and other users' nodes never see each other. Set before any ROS process starts.
# Under pytest-xdist each worker inherits the controller's environment: each takes a domain of
# its own next to it, so two workers' nodes never meet either.
_WORKER = os.environ.get("PYTEST_XDIST_WORKER", "")
if _WORKER.startswith("gw"):
    _BASE = int(os.environ.get("ROS_DOMAIN_ID") or 100 + os.getppid() % 100)
    os.environ["ROS_DOMAIN_ID"] = str(100 + (_BASE - 100 + 1 + int(_WORKER[2:])) % 100)
else:
    os.environ.setdefault("ROS_DOMAIN_ID", str(100 + os.getpid() % 100))
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"


def pytest_configure(config: pytest.Config) -> None:
    if "tuilaunch_demos" not in known_packages():
        raise pytest.UsageError(
            "the demo package is not installed: pip install ./examples/tuilaunch_demos")


@pytest.fixture
def write(tmp_path: Path):
    """Writes a launch file (dedented) into the test's folder and returns its path."""

    def _write(text: str, name: str = "test_launch.py") -> Path:
        path = tmp_path / name
        path.write_text(textwrap.dedent(text))
        return path

    return _write


def plan_of(path: Path | str, **arguments: Any) -> Plan:
    args = {k: str(v) for k, v in arguments.items()}
    return resolve(load_file(str(path)), args)


def enabled_names(plan: Plan) -> set[str]:
    return {p.full_name or p.label for p in plan.processes if p.enabled}


def run_cli(*args: str, env: dict[str, str] | None = None, timeout: float = 120) -> \
        subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "tuilaunch", *args], capture_output=True,
                          text=True, timeout=timeout, env={**os.environ, **(env or {})})


def sl_file(body: str, header: str = "from simple_launch import SimpleLauncher\n") -> str:
    """A simple_launch launch file: `header`, then a generate_launch_description that makes
    `sl = SimpleLauncher()`, runs `body` (lines at the function's indent) and returns
    `sl.launch_description()`. Its first line of `body` is line 5 of the file."""
    return (header + "\ndef generate_launch_description():\n    sl = SimpleLauncher()\n"
            + body.removeprefix("\n") + "    return sl.launch_description()\n")


def python_prints(code: str, timeout: float = 120) -> str:
    """What a fresh interpreter running `code` prints; it must exit 0."""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=timeout)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout



@contextmanager
def session_folders(log_dir: Path, prefix: Path | None = None) -> Iterator[Path]:
    """A private session folder (short: socket paths are limited) and log folder for the
    sessions started inside, with `prefix` first on AMENT_PREFIX_PATH; a session server
    left running by a failed stop is killed at the end. Yields the session folder."""
    runtime = Path(tempfile.mkdtemp(prefix="tl"))
    patch = pytest.MonkeyPatch()
    patch.setenv("XDG_RUNTIME_DIR", str(runtime))
    patch.setenv("ROS_LOG_DIR", str(log_dir))
    if prefix is not None:
        patch.setenv("AMENT_PREFIX_PATH", os.pathsep.join(
            [str(prefix), os.environ.get("AMENT_PREFIX_PATH", "")]))
    try:
        yield runtime
    finally:
        for info in (runtime / "tuilaunch").glob("*.json"):  # a failed stop leaves none
            try:
                os.kill(json.loads(info.read_text())["pid"], signal.SIGKILL)
            except (ProcessLookupError, ValueError, KeyError):
                pass
        patch.undo()

def wait_for(check: Callable[[], object], timeout: float = 60.0, what: str = "") -> None:
    """Polls `check` until it holds. The timeout only guards against a hang (a busy machine
    is slow, never wrong); when it runs out the failure names what was awaited."""
    end = time.monotonic() + timeout
    while not check():
        assert time.monotonic() < end, f"never happened within {timeout:g} s: {what or check}"
        time.sleep(0.05)


def run_headless(path: Path, *args: str, timeout: float = 90,
                 until: tuple[str, ...] | Callable[[str], bool] = (),
                 env: dict[str, str] | None = None) -> str:
    """Runs the file headless until every text in `until` was printed (or `until(output)`
    holds), then sends SIGINT.

    The timeout only guards against a hang, and holds even when the launch prints nothing;
    the assertions then say what was missing."""
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", str(path), *args, "--headless"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env={**os.environ, **(env or {})}, start_new_session=True)
    seen: list[str] = []
    lines: queue.Queue[str | None] = queue.Queue()
    stdout = proc.stdout
    assert stdout is not None

    def read() -> None:  # a thread, so that a silent launch cannot outlast the deadline
        for line in stdout:
            lines.put(line)
        lines.put(None)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        limit = time.monotonic() + timeout
        while (left := limit - time.monotonic()) > 0:
            try:
                line = lines.get(timeout=left)
            except queue.Empty:
                break
            if line is None:
                break
            seen.append(line)
            if callable(until):
                if until("".join(seen)):
                    break
            elif all(any(text in earlier for earlier in seen) for text in until):
                break
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=60)
        reader.join(timeout=30)
        while not lines.empty():
            rest = lines.get()
            if rest is not None:
                seen.append(rest)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    return "".join(seen)
