"""`--headless`: run the plan and print every line as `[id] line`, like ros2 launch.

Ctrl+C stops the launch (SIGINT to every process, then SIGTERM and SIGKILL after their
timeouts, each step announced); a second Ctrl+C sends SIGTERM at once, a third SIGKILL.
SIGTERM and SIGQUIT print ros2 launch's `user interrupted with ctrl-\\ (SIGTERM),
terminating...` and end with its exit status 1, but stop every process as Ctrl+C does;
SIGHUP stops it as Ctrl+C does.
A closed or dead stdout (`| head`, a dropped ssh link) is said once on stderr and changes
nothing else: the nodes run on and every line still goes to their log files.
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, TextIO, cast

from ..engine.launcher import make_supervisor
from ..engine.plan.model import Plan
from ..engine.ros.actions import exit_now_if_hung
from ..engine.run.events import (
    ActionFinished,
    ComponentReport,
    Event,
    Failed,
    LifecycleChanged,
    Log,
    Output,
    ProcessExited,
    Respawning,
    Shutdown,
    Started,
    Stopping,
)
from ..engine.run.supervisor.stopping import CTRL_C_REASON
from ..engine.run.vocabulary.text import strip_ansi
from .stdout_writer import BackgroundWriter, LineJoiner

if TYPE_CHECKING:
    from ..engine.plan.machines import Placement


def run_log_dir() -> Path:
    base = os.environ.get("ROS_LOG_DIR") or os.path.join(
        os.environ.get("ROS_HOME") or os.path.expanduser("~/.ros"), "log")
    stamp = time.strftime("%Y-%m-%d-%H-%M-%S")
    return Path(base) / f"{stamp}-tuilaunch-{os.getpid()}"


class _FormatSubject:
    """What `{this...}` reaches in an output_format: the names launch's action has."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.process_description = self
        self.final_name = name
        self.process_details = {"name": name}


class Printer:
    """Writes events to a stream; strips colour codes unless the stream is a terminal.

    A stream with a file descriptor is written from a thread of its own (`BackgroundWriter`),
    so a reader that stops reading never holds up the launch."""

    def __init__(self, out: TextIO, log_dir: Path | None = None,
                 plan: Plan | None = None) -> None:
        self.out = out
        self.log_dir = log_dir
        self.commands = {p.id: p.cmd for p in plan.processes} if plan is not None else {}
        # a process another machine runs is labelled with it: `[talker-1@nuc] ...`
        self.labels = {p.id: f"{p.id}@{p.machine}" for p in plan.processes
                       if p.machine} if plan is not None else {}
        # the streams a process's `output` keeps off the screen ('log': its stdout), as
        # ros2 launch prints them; its log file has them
        self.unshown = {p.id: {"stdout", "stderr"} - set(p.screen) for p in plan.processes
                        if len(p.screen) < 2} if plan is not None else {}
        self.formats = {p.id: p.output_format for p in plan.processes
                        if p.output_format} if plan is not None else {}
        self.broken: str | None = None
        try:
            self.colour = out.isatty() and not os.environ.get("NO_COLOR")
        except ValueError:
            self.colour = False
        self.writer: BackgroundWriter | None = None
        self.joined: LineJoiner | None = None
        try:
            fd = out.fileno()
            out.flush()
        except (OSError, ValueError, AttributeError):
            return  # a stream in memory: written directly
        self.writer = BackgroundWriter(fd, getattr(out, "encoding", None) or "utf-8",
                                       self._give_up, self._skipped)
        if out is sys.stdout:  # what launch code prints goes the writer's way, whole lines
            self.joined = LineJoiner(self.writer, out)
            sys.stdout = cast(TextIO, self.joined)

    def __call__(self, event: Event) -> None:
        if self.broken is not None:
            return
        text = self.format(event)
        if not text:
            return
        if self.writer is not None:
            self.writer.write(text, len(event.lines) if isinstance(event, Output) else 0)
            return
        try:
            self.out.write(text)
            self.out.flush()
        except (OSError, ValueError) as exc:
            self._give_up(exc)

    def close(self) -> None:
        """Writes what is still queued, as long as the reader keeps taking it."""
        if self.joined is not None and sys.stdout is self.joined:
            self.joined.flush()
            sys.stdout = self.out
        if self.writer is not None:
            self.writer.close()

    def _skipped(self, count: int) -> str:
        where = f" below {self.log_dir}" if self.log_dir else ""
        return (f"[WARN] [launch]: {count} output lines not shown: stdout did not keep up "
                f"(they are in the log files{where})\n")

    def format(self, event: Event) -> str:
        if isinstance(event, Output):
            if not event.lines:
                return ""  # an unfinished line shown by a TUI: printed once it is whole
            if event.stream in self.unshown.get(event.process or "", ()):
                return ""
            form = self.formats.get(event.process or "")
            text = self._prefixed(event) if form is None else self._formatted(form, event)
            return text if self.colour or "\x1b" not in text else strip_ansi(text)
        if isinstance(event, (Started, ActionFinished)) and event.pid is None:
            return ""  # an action's progress: its log lines already say what happened
        if isinstance(event, Stopping):
            return ""  # as in launch, its signal's line says it (`sending signal ...`)
        if isinstance(event, Started):
            return f"[INFO] [{self.label(event)}]: process started with pid [{event.pid}]\n"
        if isinstance(event, ProcessExited):
            return self._exit_line(event)
        if isinstance(event, Failed):
            return f"[ERROR] [{self.label(event)}]: failed to start: {event.reason}\n"
        if isinstance(event, Respawning):
            return f"[WARN] [{self.label(event)}]: respawning ({event.reason})\n"
        if isinstance(event, LifecycleChanged):
            return f"[INFO] [{self.label(event)}]: lifecycle state {event.reason}\n" \
                if event.reason else ""
        if isinstance(event, ComponentReport):
            if event.data and event.data.get("state") == "loading":
                return ""  # "waiting for the service": the result line follows
            return f"[{event.level}] [{self.label(event)}]: {event.reason}\n"
        if isinstance(event, Log):
            # LogInfo speaks as launch.user, as in ros2 launch (people grep for it)
            who = (event.data or {}).get("logger") or event.process or "launch.user"
            return f"[{event.level}] [{who}]: {event.reason}\n"
        if isinstance(event, Shutdown) and (event.data or {}).get("launch"):
            # launch logs no reason for its ways to end (launch_service.py,
            # shutdown_action.py): its own lines (`user interrupted with ctrl-c (SIGINT)`,
            # `process[x] was required: ...`) are printed where it prints them
            return ""
        return f"[INFO] [launch]: {event.kind} ({event.reason})\n"

    def _formatted(self, form: str, event: Event) -> str:
        """launch's `output_format.format(line=..., this=the action)`: `this` answers for
        the process's name as launch's action does (`this.process_description.final_name`,
        `this.name`); a format naming anything else falls back to `[name] line`."""
        this = _FormatSubject(self.label(event) or "")
        try:
            return "".join(form.format(line=line, this=this) + "\n" for line in event.lines)
        except (AttributeError, IndexError, KeyError, ValueError):
            return self._prefixed(event)

    def _prefixed(self, event: Event) -> str:
        """`[name] line` for each line: launch's default output_format."""
        prefix = f"[{self.label(event)}] "
        return prefix + ("\n" + prefix).join(event.lines) + "\n"

    def _exit_line(self, event: ProcessExited) -> str:
        """ros2 launch's words, so that what greps its output greps ours."""
        if event.code == 0:
            return f"[INFO] [{self.label(event)}]: process has finished cleanly " \
                f"[pid {event.pid}]\n"
        if event.asked:
            # the stop asked for (Ctrl+C, `tuilaunch stop`): its end is no error to report
            return f"[INFO] [{self.label(event)}]: process stopped [pid {event.pid}, " \
                f"{event.reason}]\n"
        code = f"{event.code}" if event.code is None or event.code >= 0 else \
            f"{event.code} ({event.reason})"
        cmd = " ".join(part for part in self.commands.get(event.process or "", [])
                       if part.strip())
        return f"[ERROR] [{self.label(event)}]: process has died [pid {event.pid}, exit code " \
            f"{code}, cmd '{cmd}'].\n"

    def label(self, event: Event) -> str | None:
        return self.labels.get(event.process or "", event.process)

    def say(self, text: str) -> None:
        self(Log("launch", reason=text))

    def _give_up(self, exc: Exception) -> None:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        self.broken = reason
        where = f" below {self.log_dir}" if self.log_dir else ""
        try:
            sys.stderr.write(f"tuilaunch: cannot write to stdout ({reason}): the launch goes "
                             f"on; every node's output is in its log file{where}\n")
            sys.stderr.flush()
        except (OSError, ValueError):
            pass  # the terminal is gone altogether
        # what is still buffered must not fail again at exit
        try:
            fd = self.out.fileno()
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, fd)
            os.close(devnull)
        except (OSError, ValueError, AttributeError):
            pass


async def _run(plan: Plan, log_dir: Path, placement: Placement | None = None,
               command: list[str] | None = None,
               arguments: dict[str, str] | None = None) -> int:
    supervisor = make_supervisor(plan, log_dir, placement=placement, command=command,
                                 arguments=arguments, served=False)
    printer = Printer(sys.stdout, log_dir, plan)
    supervisor.subscribe(printer)
    loop = asyncio.get_running_loop()

    stopping: set[asyncio.Task[None]] = set()  # held so the task is not collected mid-run
    asked = 0
    terminated = False

    def on_signal(sig: signal.Signals) -> None:
        nonlocal asked, terminated
        asked += 1
        if asked == 1:
            # ros2 launch's reason for Ctrl+C; it has none for the others (it cancels)
            reason = CTRL_C_REASON if sig == signal.SIGINT else f"received {sig.name}"
            if sig in (signal.SIGTERM, signal.SIGQUIT):
                # ros2 launch's words (launch_service.py's _on_sigterm), and its exit status
                # 1 (its run is cancelled); unlike it, tuilaunch still stops every process
                terminated = True
                printer(Log("launch", level="ERROR",
                            reason=f"user interrupted with ctrl-\\ ({sig.name}), "
                            "terminating..."))
            stopping.add(asyncio.ensure_future(supervisor.shutdown(reason)))
            if sig == signal.SIGINT:
                # ros2 launch's line, which people grep for
                printer(Log("launch", reason="user interrupted with ctrl-c (SIGINT)",
                            level="WARNING"))
                printer.say("stopping: Ctrl+C again sends SIGTERM now, a third time SIGKILL")
            return
        sent = supervisor.escalate_now()
        if sent is not None:
            printer.say(f"received {sig.name} again: sending {sent} now")

    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT):
        loop.add_signal_handler(sig, on_signal, sig)
    # ros2 launch's first two lines (launch.logging.log_launch_config); tuilaunch logs at
    # INFO whatever --debug says (that flag asks for tracebacks)
    printer(Log("launch", reason=f"All log files can be found below {log_dir}"))
    printer(Log("launch", reason="Default logging verbosity is set to INFO"))
    try:
        status = await supervisor.run()
        return (status or 1) if terminated else status
    finally:
        printer.close()


def run_headless(plan: Plan, log_dir: Path | None = None, placement: Placement | None = None,
                 command: list[str] | None = None,
                 arguments: dict[str, str] | None = None) -> int:
    """`placement` (`--machines`, applied to `plan`): its other machines run their share,
    started with `command` (FILE or PACKAGE FILE as given) and `arguments`."""
    status = asyncio.run(_run(plan, log_dir or run_log_dir(), placement, command, arguments))
    exit_now_if_hung(status)  # rclpy's shutdown hung: the DDS library's exit would too
    return status
