"""tuilaunch works from whatever folder the user is in: its own processes (the session
server, a browser tab's TUI) are started with `python -P -m`, so a folder named `tuilaunch`
in the current directory (the session folder itself, when the user stands in
$XDG_RUNTIME_DIR) is never imported in place of the package."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from ..conftest import wait_for

LAUNCH = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess


def generate_launch_description():
    return LaunchDescription([ExecuteProcess(cmd=["sleep", "600"], name="idle")])
"""


def tuilaunch(*args: str, cwd: Path, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    """The command as the user types it, in `cwd`."""
    command = Path(sys.executable).parent / "tuilaunch"
    return subprocess.run([str(command), *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=120)


def test_a_session_started_from_the_runtime_folder_runs(tmp_path: Path) -> None:
    runtime = tmp_path / "run"
    runtime.mkdir(mode=0o700)
    (runtime / "tuilaunch").mkdir(mode=0o700)  # the session folder, where the user stands
    launch = tmp_path / "idle.launch.py"
    launch.write_text(LAUNCH)
    env = {**os.environ, "XDG_RUNTIME_DIR": str(runtime)}
    started = tuilaunch(str(launch), "--detach", "--name", "here", cwd=runtime, env=env)
    try:
        assert started.returncode == 0, started.stderr
        wait_for(lambda: "running" in tuilaunch("status", "here", cwd=runtime, env=env).stdout,
                 timeout=90, what="the session's process running")
    finally:
        stopped = tuilaunch("stop", "here", cwd=runtime, env=env)
    assert stopped.returncode == 0, stopped.stderr
    assert tuilaunch("ls", cwd=runtime, env=env).stdout.startswith("no running sessions")
