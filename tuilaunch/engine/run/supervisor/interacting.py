"""The operator's hands on one process: typing into its terminal (here, or on the machine
that runs it: `take_keys`, `type_keys`), running it under a tool (gdb, valgrind...) or at
another log level, and the exact command it was started with."""

from __future__ import annotations

from typing import Any

from ...errors import LaunchError
from ...plan.command.prefix import with_prefix
from ..process.process_command import check_log_level, describe_command
from ..process.readers import NO_TERMINAL, Running
from ..process.terminal_input import InputRefused
from .core import SupervisorCore
from .starting import Starting


class Interacting:
    """Typing into a process, restart options, and its command for `status`. What it would
    start with now is `starting`'s to say (starting.py), as it starts it."""

    def __init__(self, core: SupervisorCore, starting: Starting) -> None:
        self.core = core
        self.starting = starting

    def running_process(self, process_id: str) -> Running | None:
        """The running process's record (its pid, its terminal), or None."""
        return self.core.running.get(process_id)

    def write_input(self, process_id: str, data: bytes) -> int:
        """Types `data` into a running process's terminal (`\\r` for Enter, `\\x03` for
        ctrl+c: SIGINT to a line reader, a key to a raw one); returns the bytes dropped
        because it does not read them. LaunchError, one line naming it, when it cannot be
        typed into (not running, no terminal)."""
        running = self.core.running.get(process_id)
        if running is None:
            raise LaunchError(f"{process_id} is not running ({self.core.states.get(process_id)}):"
                              " there is nothing to type into")
        try:
            return running.write_input(data)
        except InputRefused as exc:
            raise LaunchError(f"{process_id} cannot be typed into: {exc}") from None

    async def take_keys(self, process_id: str) -> None:
        """Checks that `process_id` can be typed into, before a client takes its keyboard:
        a terminal here, or, run on another machine, its keyboard there taken for this
        side (its machine says why not: the terminal it gave it is its own to know).
        LaunchError, one line, when it cannot."""
        core = self.core
        if not core.runs_here(process_id):
            await core.placing.keys_of(core.plan, process_id).take_keys(process_id)
            return
        running = core.running.get(process_id)
        if running is None or running.terminal is None:
            raise LaunchError(f"{process_id} cannot be typed into: {NO_TERMINAL}")

    def give_keys(self, process_id: str) -> None:
        """The client typing into `process_id` let go: run elsewhere, so does this side."""
        core = self.core
        if not core.runs_here(process_id) and core.placing.remote is not None:
            core.placing.remote.requests.give_keys(process_id)

    async def type_keys(self, process_id: str, data: bytes) -> int:
        """`write_input`, for a process here or on another machine (the keys are sent
        there, in order); the bytes it dropped."""
        core = self.core
        if core.runs_here(process_id):
            return self.write_input(process_id, data)
        return await core.placing.keys_of(core.plan, process_id).type_keys(process_id, data)

    def restart_options(self, process_id: str, prefix: str | None = None,
                        log_level: str | None = None, terminal: bool = False) -> None:
        """Checks and records what the next start of `process_id` runs with, before anything
        is stopped: a bad prefix or level changes nothing.

        `prefix` (a tool and its options) and `terminal` (a terminal to type into, for a
        process the file gives pipes) hold for the runs from this restart (respawns
        included) until a restart without them; `log_level` holds until a restart gives
        another (an empty one goes back to the file's)."""
        core = self.core
        proc = core.plan.process(process_id)
        level = None
        if log_level:
            if proc.kind == "process":
                raise LaunchError(f"{process_id} is not a ROS node (an ExecuteProcess): "
                                  "--log-level does not apply to it")
            level = check_log_level(log_level)
        if prefix:
            with_prefix(list(proc.cmd), prefix)  # a tool not on PATH fails here
        record = core.records[process_id]
        record.prefix, record.terminal = prefix or None, terminal
        if level or log_level is not None:  # "" clears it; None leaves it as it was
            record.log_level = level or None

    def command_of(self, process_id: str) -> dict[str, Any]:
        """`command`, `command_line` and `env` of the process's last start, or of the
        start it would get now when it has not started yet."""
        start = self.core.records[process_id].started_with
        if start is None:
            proc = self.core.plan.process(process_id)
            if not proc.cmd:
                return {}
            try:
                start = self.starting.command_for(proc)
            except LaunchError:
                return {}
        return describe_command(start, self.starting.base_env())
