"""The exact command of a process, pasted into a shell, runs the same program the same way."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tuilaunch.engine.plan.command.shell_command import env_changes, shell_command

SHOW = ("import json, os, sys; print(json.dumps({'argv': sys.argv[1:], 'cwd': os.getcwd(), "
        "'A': os.environ.get('TL_A'), 'GONE': os.environ.get('TL_GONE'), "
        "'HOME': os.environ.get('HOME')}))")


def run_line(line: str, base: dict[str, str]) -> dict[str, object]:
    out = subprocess.run(["sh", "-c", line], env=base, capture_output=True, text=True,
                         check=True, timeout=60).stdout
    return dict(json.loads(out))


def test_pasted_line_gives_the_same_argv_cwd_and_environment(tmp_path: Path) -> None:
    base = dict(os.environ, TL_GONE="x")
    final = dict(base, TL_A="it's a 'value' with $HOME")
    del final["TL_GONE"]
    changed, removed = env_changes(base, final)
    assert changed == {"TL_A": "it's a 'value' with $HOME"} and removed == ["TL_GONE"]
    cmd = [sys.executable, "-c", SHOW, "--ros-args", "-p", "msg:='hi there'", "*"]
    line = shell_command(cmd, changed, str(tmp_path), unset=removed)
    seen = run_line(line, base)
    assert seen["argv"] == cmd[3:]
    assert seen["cwd"] == str(tmp_path)
    assert seen["A"] == "it's a 'value' with $HOME" and seen["GONE"] is None


def test_a_cleared_environment_is_env_i(tmp_path: Path) -> None:
    line = shell_command([sys.executable, "-c", SHOW], {"TL_A": "1"}, clear_env=True)
    assert line.startswith("env -i -- TL_A=1 ")
    seen = run_line(line, dict(os.environ))
    assert seen["A"] == "1" and seen["HOME"] is None


def test_no_changes_is_the_bare_command() -> None:
    assert shell_command(["talker", "--ros-args"]) == "talker --ros-args"
