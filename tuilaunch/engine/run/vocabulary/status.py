"""`status`'s reply as dataclasses: the session (what its info file says), each process's
state, command and figures, the actions, who types where. The server builds a StatusReply
(session/session_server.py `status`); request.py's codec writes it as JSON and reads it back
for every client (`Status(...).reply`), so the command line, the TUI and the launching side
of a placed launch read attributes, never string keys.

The JSON is the wire of the untyped server, key for key (`tuilaunch status --json` prints
`to_json()`): a field that server wrote only when it knew it (a process's command, a
crash's signal) is `absent_when_none`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .request import absent_when_none, reply_to_json

ABSENT = absent_when_none()
"""A field written only when known, as the untyped server did."""
COMMAND_FIELDS = ("command", "command_line", "env", "unset_env", "terminal")
"""What a process's status says of how it was started (a placed process's, by its machine)."""


def _terminal_said(process: ProcessStatus) -> bool:
    """`terminal` is written, None meaning "not known here", with a known command, and for
    a process with a machine (one placed elsewhere: its terminal is that machine's to
    know)."""
    return process.command is not None or process.machine is not None


@dataclass(frozen=True)
class ProcessStatus:
    """One process of the plan: `state`; `pid` while it runs; `exit_code` of its last end
    until it starts again; `detail`, why it is not running; its figures when asked
    (`resources`) and it runs; how its last start was made (its next one's, before any),
    `signal` and `core` when a signal nobody asked for killed it."""

    id: str
    name: str = ""
    state: str = "pending"
    pid: int | None = None
    exit_code: int | None = None
    detail: str | None = None
    machine: str | None = None
    cpu_percent: float | None = None
    rss_bytes: int | None = None
    threads: int | None = None
    command: list[str] | None = field(default=None, metadata=ABSENT)
    command_line: str | None = field(default=None, metadata=ABSENT)
    env: dict[str, str] | None = field(default=None, metadata=ABSENT)
    unset_env: list[str] | None = field(default=None, metadata=ABSENT)
    terminal: bool | None = field(default=None, metadata=absent_when_none(_terminal_said))
    signal: str | None = field(default=None, metadata=ABSENT)
    core: str | None = field(default=None, metadata=ABSENT)

    def to_json(self) -> dict[str, Any]:
        written: dict[str, Any] = reply_to_json(self)
        return written

    def started_with(self) -> dict[str, Any]:
        """COMMAND_FIELDS as the JSON has them (those known)."""
        return {k: v for k, v in self.to_json().items() if k in COMMAND_FIELDS}


@dataclass(frozen=True)
class ActionStatus:
    """An action of the plan (a service call, a parameter set ...) and its state."""

    id: str
    kind: str = ""
    state: str = "pending"


@dataclass(frozen=True)
class Typing:
    """The client that holds a process's keyboard."""

    client: int
    process: str


@dataclass(frozen=True)
class PlacementInfo:
    """`--machines` as the launch was given it (plan/machines.py `placement_from_text`)."""

    text: str
    path: str
    share: str | None = None


@dataclass(frozen=True)
class StatusReply:
    """A session's status: its info (what `ls` lists, what `attach` needs to draw it), the
    count of its processes by state, each process, each action, the clients dropped for
    falling behind, who types where."""

    name: str = ""
    file: str = ""
    command: list[str] = field(default_factory=list)
    arguments: dict[str, str] = field(default_factory=dict)
    pid: int = 0
    started: float = 0.0
    log_dir: str = ""
    file_stamp: list[int] | None = None
    """The launch file's (mtime ns, size) when the plan that runs was read from it."""
    protocol: int | None = field(default=None, metadata=ABSENT)
    tuilaunch: str | None = field(default=None, metadata=ABSENT)
    placement: PlacementInfo | None = field(default=None, metadata=ABSENT)
    counts: dict[str, int] = field(default_factory=dict)
    processes: list[ProcessStatus] = field(default_factory=list)
    actions: list[ActionStatus] = field(default_factory=list)
    dropped_clients: int = 0
    typing: Typing | None = None

    def to_json(self) -> dict[str, Any]:
        """The reply as the wire has it (`status --json` prints it)."""
        written: dict[str, Any] = reply_to_json(self)
        return written

    def process(self, process_id: str) -> ProcessStatus | None:
        return next((p for p in self.processes if p.id == process_id), None)

    def listing(self) -> dict[str, Any]:
        """Its row in `ls --json` (and `__ls`), but for `answering`."""
        return {"name": self.name, "file": self.file, "arguments": self.arguments,
                "pid": self.pid, "started": self.started, "log_dir": self.log_dir,
                "counts": self.counts}


__all__ = ["COMMAND_FIELDS", "ActionStatus", "PlacementInfo", "ProcessStatus", "StatusReply",
           "Typing"]
