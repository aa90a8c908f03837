"""What a process is started with: its argv (with an operator's tool prefix or log level for
this run), its environment, its directory; that as a paste-ready shell line; and what is
known of a death nobody asked for (the signal, the core).

The supervisor builds a process's start from here (run/supervisor/starting.py) and the
session server reports the same thing in `status`, so the line an operator pastes is the
one that ran.
"""

from __future__ import annotations

import os
import time
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ...errors import LaunchError
from ...plan.command.prefix import with_prefix
from ...plan.command.shell_command import env_changes, shell_command
from ...plan.model import ProcessPlan
from .cores import core_location, is_crash, signal_name

LOG_LEVELS = ("debug", "info", "warn", "error", "fatal", "unset")
"""What rcl accepts after `--log-level` (with an optional `logger_name:=` before it)."""


@dataclass
class StartCommand:
    """One start of a process: exactly what is handed to spawn."""

    cmd: list[str]
    env: dict[str, str]
    cwd: str | None
    clear_env: bool
    tty: bool
    controlling_terminal: bool
    """Under a tool (gdb, pdb): its terminal controls it, for the job control it needs."""


def check_log_level(level: str) -> str:
    """`debug`, `DEBUG` or `my_node:=debug`, as `--ros-args --log-level` takes it; one line
    naming the value otherwise."""
    text = level.strip()
    name, _, severity = text.rpartition(":=")
    if severity.lower() not in LOG_LEVELS or (":=" in text and not name):
        raise LaunchError(f"log level {level!r} is not one of {', '.join(LOG_LEVELS)} "
                          "(optionally LOGGER:=LEVEL)")
    return f"{name}:={severity.lower()}" if name else severity.lower()


def start_command(proc: ProcessPlan, base_env: Mapping[str, str], tty: bool,
                  prefix: str | None = None, log_level: str | None = None) -> StartCommand:
    """The plan's command, plus `--ros-args --log-level LEVEL` (as ros2 run appends it) and
    an operator's tool before it (`gdb -q -ex run --args`), with the environment the
    supervisor gives every child. A prefixed run always gets a terminal: its tool is typed
    into."""
    cmd = list(proc.cmd)
    if log_level:
        cmd += ["--ros-args", "--log-level", log_level]
    if prefix:
        cmd = with_prefix(cmd, prefix)
    env = {} if proc.clear_env else dict(base_env)
    for name in proc.unset_env:  # an UnsetEnvironmentVariable in its scope, as in launch
        env.pop(name, None)
    env.update(proc.env)
    env.setdefault("PYTHONUNBUFFERED", "1")
    env.setdefault("RCUTILS_LOGGING_BUFFERED_STREAM", "1")
    env.setdefault("RCUTILS_COLORIZED_OUTPUT", "0" if os.environ.get("NO_COLOR") else "1")
    return StartCommand(cmd, env, proc.cwd, proc.clear_env, tty or bool(prefix), bool(prefix))


def describe_command(start: StartCommand, base_env: Mapping[str, str]) -> dict[str, Any]:
    """`status`'s view of a start: `command` (argv), `command_line` (for a shell: `cd`,
    `env` changes, the argv quoted), `env` (what differs from the launcher's) and `unset_env`
    (the launcher's variables it does not get), `terminal` (a terminal, or pipes)."""
    changed, removed = env_changes(base_env, start.env)
    removed = [] if start.clear_env else removed
    line = shell_command(start.cmd, start.env if start.clear_env else changed, start.cwd,
                         unset=removed, clear_env=start.clear_env)
    return {"command": list(start.cmd), "command_line": line, "env": changed,
            "unset_env": removed, "terminal": start.tty}


def death_details(pid: int, code: int, requested: bool, cwd: str | None, comm: str,
                  started: float) -> dict[str, str]:
    """For a death by a signal nobody asked for: `signal` (its name) and `core` (where the
    system kept the core) when known; empty otherwise. `started` is time.monotonic()'s."""
    if not is_crash(code, requested):
        return {}
    details = {"signal": signal_name(-code)}
    since = time.time() - (time.monotonic() - started)
    where = core_location(pid, -code, cwd, comm=comm, since=since)
    if where is not None:
        details["core"] = where
    return details
