"""Starting a process: parameter files, environment, log file, spawn, and watching its exit.

No thread per child: each child's exit is watched through a pidfd on the event loop, and
its output through non-blocking reads on the same loop.
"""

from __future__ import annotations

import asyncio
import os
import signal
import time
from collections.abc import Callable
from pathlib import Path

from ...errors import LaunchError
from ...plan.model import ProcessPlan
from ...plan.params import write_parameter_file
from ..events import ExitCause, Failed, Log, Output, ProcessExited, Respawning, Started
from ..process.logfiles import LogFile
from ..process.process_command import StartCommand, death_details, start_command
from ..process.readers import ChannelReader, Running
from ..process.spawn import spawn
from ..vocabulary.requests import Start
from .core import SupervisorCore
from .placed import ELSEWHERE
from .plan_actions import PlanActions
from .stopping import describe_exit, group_alive, kill_group

_ENDING_KEYS = {signal.SIGINT, signal.SIGQUIT}
"""Signals of keys typed into a node (ctrl+c, ctrl+\\) that end it on the operator's request."""

EOF_GRACE = 1.0
"""Seconds to wait, once a process is reaped, for the end of its output. A daemonised
grandchild may hold the pipe for ever: its exit is then reported anyway, and whatever it
still prints is read and logged until the launch ends, and what waits in the channel then
is read before it is closed (ChannelReader.close)."""


class Starting:
    """Starting a process, following it until it has exited, and bringing it back (the
    policy is the Respawner's, respawn.py). Its start, its output and its exit set off the
    plan's handlers: `actions` (plan_actions.py)."""

    def __init__(self, core: SupervisorCore, actions: PlanActions) -> None:
        self.core = core
        self.actions = actions

    async def start(self, process_id: str, respawn: bool = False) -> None:
        """Starts one process (also a stopped or exited one, from the UI), here or on its
        machine; `respawn`: it comes back after a crash, counted by the Respawner (an
        operator's start counts from zero again)."""
        core = self.core
        proc = core.plan.process(process_id)
        if not proc.enabled:
            # a node its condition skipped is not part of the launch: no client (a group's
            # `t`, a fleet's, `tuilaunch start`) starts it; a relaunch whose values enable
            # it does
            why = f" ({proc.skipped_by.expression} = {proc.skipped_by.value!r})" \
                if proc.skipped_by is not None else ""
            raise LaunchError(f"{process_id} is skipped by its condition{why}: the launch "
                              "does not run it")
        if not respawn:
            core.respawner.forget(process_id)
        record = core.records[process_id]
        waiting, record.respawn_wait = record.respawn_wait, None
        if waiting is not None:
            waiting.set()  # started now by the operator: the respawn under way is moot
        ending = core.running.get(process_id)
        if ending is not None and ending.exited.done():
            await ending.gone.wait()  # it exited on its own a moment ago: its end first
        if core.runs_here(process_id):
            self.start_now(process_id)
        elif core.placing.remote is None:
            core.states[process_id] = ELSEWHERE  # its own machine starts it
        else:
            await core.placing.forward(core.plan, Start(process_id))

    def start_now(self, process_id: str) -> None:
        """From the check that the launch is not shutting down to the registration of the
        child nothing awaits, so a shutdown either prevents the start or sees the child."""
        core = self.core
        proc = core.plan.process(process_id)
        if process_id in core.running or core.shutting_down:
            return
        if proc.error:
            where = f" ({proc.origin})" if proc.origin else ""
            self._fail(process_id, proc.error + where)
            return
        try:
            for path, values in proc.generated_parameter_files:
                write_parameter_file(Path(path), values)
        except Exception as exc:  # a LaunchError or an OSError: either way, one line
            self._fail(process_id, f"cannot write its parameter file: {exc}")
            return
        try:
            start = self.command_for(proc)
        except LaunchError as exc:  # the tool left PATH since the restart checked it
            self._fail(process_id, str(exc))
            return
        record = core.records[process_id]
        record.started_with, record.death = start, None  # a death is said until a start
        env = dict(start.env)
        core.watchdog.start()
        if core.watchdog.error and "watchdog" not in core.reported:
            core.reported.add("watchdog")
            core.report_io(f"{core.watchdog.error}: processes may outlive a crash of "
                           "tuilaunch")
        core.watchdog.mark(env)
        log_path = core.log_dir / f"{process_id}.log"
        try:
            log = LogFile(log_path, core.report_io)
        except OSError as exc:
            self._fail(process_id, f"cannot open its log file {log_path}: "
                       f"{exc.strerror or exc}")
            return
        if proc.log_cmd:  # launch's words (ExecuteLocal); its env is always a dict now
            shown = " ".join(part for part in start.cmd if part.strip())
            core.emit(Log(process_id, reason=f"process details: cmd='{shown}', "
                          f"cwd='{start.cwd}', custom_env?=True"))
        try:
            # no controlling terminal (vfork: fast) but under a tool, whose job control
            # needs one; the terminal's writer turns ctrl+c into SIGINT otherwise
            child = spawn(start.cmd, env, start.cwd, start.tty,
                          controlling_terminal=start.controlling_terminal)
        except Exception as exc:  # OSError, or ValueError for a NUL byte in an argument
            log.close()
            what = getattr(exc, "filename", None)
            what = what if isinstance(what, str) else start.cmd[0]
            self._fail(process_id, f"cannot start {what}: "
                       f"{getattr(exc, 'strerror', None) or exc}")
            return
        popen = child.popen
        loop = asyncio.get_running_loop()
        running = None
        try:
            core.watchdog.watch(popen.pid)
            running = Running(proc, popen, log, time.monotonic(), loop.create_future())
            core.running[process_id] = running
            self._watch_exit(running)
            for channel in child.channels:
                running.readers.append(ChannelReader(running, channel, self.deliver_lines,
                                                     self.deliver_partial))
        except Exception as exc:
            # nothing may run that nobody reads or stops
            kill_group(popen.pid, signal.SIGKILL)
            popen.wait()
            if running is not None and running.pidfd is not None:
                loop.remove_reader(running.pidfd)
                close_quietly(running.pidfd)
            for channel in child.channels:
                loop.remove_reader(channel.fd)
                close_quietly(channel.fd)
            log.close()
            core.running.pop(process_id, None)
            self._fail(process_id, f"could not be tracked and was killed: "
                       f"{type(exc).__name__}: {exc}")
            return
        # followed before anything else runs: whatever raises below, its end is told
        core.spawn_task(self._wait(running))
        core.states[process_id] = "running"
        core.emit(Started(process_id, pid=popen.pid))
        self.actions.process_event(process_id, "start", popen.pid)
        core.flag(process_id, "start").set()
        for plugin in core.plugins:
            follow_up = plugin.process_started(proc)
            if follow_up is not None:
                core.spawn_task(follow_up)

    def deliver_lines(self, running: Running, stream: str, lines: list[str]) -> None:
        """A block of a process's output, already in its log file: to the consumers."""
        self.core.emit(Output(running.plan.id, stream=stream, lines=lines))
        if self.core.triggers.watches_output:
            self.actions.dispatch_io(running.plan.id, stream, lines, running.process.pid)

    def deliver_partial(self, running: Running, stream: str, text: str) -> None:
        """A line the process left unfinished (a prompt): shown until its whole line comes.
        An output event without lines, so nothing counts it as one (nor logs it)."""
        self.core.emit(Output(running.plan.id, stream=stream, data={"partial": text}))

    def command_for(self, proc: ProcessPlan) -> StartCommand:
        """What `proc` starts with now: the file's command under an operator's tool, log
        level and terminal. LaunchError when the tool is no longer on PATH."""
        return start_command(proc, self.base_env(), self.gets_tty(proc),
                             self.core.records[proc.id].prefix,
                             self.core.records[proc.id].log_level)

    def base_env(self) -> dict[str, str]:
        """tuilaunch's environment as it was at the first start: read once, not per child."""
        core = self.core
        if core.env_cache is None:
            core.env_cache = dict(os.environ)
        return core.env_cache

    def _fail(self, process_id: str, reason: str) -> None:
        self.core.states[process_id] = "failed"
        self.core.emit(Failed(process_id, reason=reason))

    def _watch_exit(self, running: Running) -> None:
        """The child's exit wakes the loop through a pidfd: no thread per child."""
        loop = asyncio.get_running_loop()
        try:
            running.pidfd = os.pidfd_open(running.process.pid)
        except (OSError, AttributeError):
            running.pidfd = None  # old kernel, or no descriptor left: poll instead
            loop.call_later(0.05, self._poll_exit, running)
            return
        loop.add_reader(running.pidfd, self._reap, running)

    def _poll_exit(self, running: Running) -> None:
        if running.process.poll() is not None:
            self._reap(running)
        else:
            asyncio.get_running_loop().call_later(0.05, self._poll_exit, running)

    def _reap(self, running: Running) -> None:
        if running.pidfd is not None:
            asyncio.get_running_loop().remove_reader(running.pidfd)
            os.close(running.pidfd)
            running.pidfd = None
        code = running.process.wait()  # a zombie by now: does not block
        if not running.exited.done():
            running.exited.set_result(code)

    async def _wait(self, running: Running) -> None:
        try:
            code, requested = await self._end(running)
        finally:
            running.gone.set()
        await self._after_end(running, code, requested)

    async def _end(self, running: Running) -> tuple[int, bool]:
        """Its exit, told once its output is read: the state, the event, the handlers.
        Returns its exit code and whether the launch asked for the end."""
        core = self.core
        code = await running.exited
        running.reaped = True
        pending = [r.done for r in running.readers if not r.done.done()]
        if pending:
            await asyncio.wait(pending, timeout=EOF_GRACE)
        lingering = [r for r in running.readers if not r.done.done()]
        core.lingering.update(lingering)
        for reader in lingering:
            reader.done.add_done_callback(self._forget_reader(reader))
        if not lingering:
            running.log.close()
        if not group_alive(running.process.pid):
            core.watchdog.forget(running.process.pid)
        process_id = running.plan.id
        del core.running[process_id]
        record = core.records[process_id]
        record.exit_code = code
        requested = running.stopping or core.shutting_down
        # a ctrl+c (or ctrl+\\, ctrl+z) typed into it was asked for by the operator too
        typed = code < 0 and -code in running.typed_signals
        if code > 0 and running.typed_signals & _ENDING_KEYS:
            typed = True  # a program that turns a typed ctrl+c into an exit status (130)
        cause = ExitCause.of(code, requested, typed)  # decided here, once
        crashed = cause is ExitCause.CRASHED
        if crashed:
            record.crash_code, record.crash_time = code, time.monotonic()
        start = record.started_with
        death = death_details(running.process.pid, code, requested or typed,
                              start.cwd if start else None,
                              os.path.basename(running.process.args[0]
                                               if running.process.args else "")[:15],
                              running.started)
        if death:
            record.death = death
        # an end nobody asked for with a signal or a non-zero status is a failure, as
        # headless ("process has died", ERROR), the tree and the exit status have it
        core.states[process_id] = "failed" if crashed else "exited"
        for plugin in core.plugins:
            plugin.process_exited(process_id)
        reason = describe_exit(code)
        if "core" in death:
            reason += f" (core: {death['core']})"
        # `requested`: a stop asked by anyone (another client, `tuilaunch stop`, a ctrl+c
        # typed into it: `typed`), not a crash
        again = {"again": True} if record.coming_back else {}
        core.emit(ProcessExited(process=process_id, pid=running.process.pid, code=code,
                                reason=reason, cause=cause,
                                data={"requested": requested or typed, "typed": typed,
                                      **again, **death}))
        self.actions.process_event(process_id, "exit", running.process.pid, code)
        core.flag(process_id, "exit").set()
        return code, requested

    async def _after_end(self, running: Running, code: int, requested: bool) -> None:
        """What follows an end the launch did not ask for: a respawn, or why not."""
        core = self.core
        process_id = running.plan.id
        tool = core.records[process_id].prefix
        if running.plan.respawn and tool and code == 0 and not requested:
            # the operator left the tool (gdb's quit): a debugging session that ended, not
            # a node to bring back under gdb again; a crash under it still respawns
            core.emit(Log(process_id, level="INFO", reason=(
                f"ended under '{tool}' with status 0: not respawned; a plain restart "
                "runs it as the file says")))
        elif self.should_respawn(running, code):
            await self.respawn(running)
        elif running.plan.respawn and not requested:
            tries = core.respawner.tries(process_id)
            ended = "failed" if code != 0 else "ended"
            core.emit(Log(process_id, level="ERROR" if code != 0 else "INFO",
                          reason=(f"respawn gives up: it {ended} {tries + 1} times "
                                    f"(respawn_max_retries="
                                    f"{running.plan.respawn_max_retries})")))

    def should_respawn(self, running: Running, code: int) -> bool:
        core = self.core
        return core.respawner.wants(running.plan, code, running.stopping or core.shutting_down)

    async def respawn(self, running: Running) -> None:
        core = self.core
        proc = running.plan
        tries, delay = core.respawner.next_try(proc, running.started)
        core.states[proc.id] = "respawning"
        core.busy += 1
        core.emit(Respawning(proc.id, reason=f"try {tries} in {delay:g} s",
                             data={"try": tries, "delay": delay}))
        record = core.records[proc.id]
        called_off = record.respawn_wait = asyncio.Event()
        try:
            await asyncio.wait_for(called_off.wait(), delay)
        except TimeoutError:
            pass  # the delay is over: it comes back
        finally:
            core.busy -= 1
            if record.respawn_wait is called_off:
                record.respawn_wait = None
        # called off: a stop (it stays down) or a start (it runs already) came meanwhile,
        # and said so itself
        if not called_off.is_set() and not core.shutting_down:
            await self.start(proc.id, respawn=True)

    def gets_tty(self, proc: ProcessPlan) -> bool:
        """The file's choice, or a terminal an operator's restart asked for."""
        return wants_tty(proc) or self.core.records[proc.id].terminal

    def _forget_reader(self, reader: ChannelReader) -> Callable[[asyncio.Future[None]], None]:
        return lambda _: self.core.lingering.discard(reader)


def wants_tty(proc: ProcessPlan) -> bool:
    """A terminal only when the file (or `emulate_tty:=true`) asks, as launch's default is:
    a pipe costs a writer less than half what a terminal does per write (a flood of lines
    shows it), and a program sees what it sees under ros2 launch (no terminal; C stdio
    holds stdout in a buffer). docs/command-line.md, "Pipes, or a terminal", says what a
    terminal gives."""
    return bool(getattr(proc, "emulate_tty", None))


def close_quietly(fd: int) -> None:
    try:
        os.close(fd)
    except OSError:
        pass
