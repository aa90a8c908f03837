"""The launching side of a launch placed on several machines (`--machines`).

For each other machine that has processes to run, the coordinator starts that machine's
share as a session of its own there (`ssh HOST tuilaunch FILE args... --detach --name NAME
--share MACHINE --machines-text YAML`), then follows it over ssh through a Connection, as
every client does (`open_remote_connection`; its Reconnector paces a new link): the share's
events of its own processes are mirrored into this supervisor (`Supervisor.mirror`), so the
one tree, the panes, the log files and the triggers here see them as local ones. What
happens here (and on the other shares) to processes a share waits for is sent to it
(`external_event`); a start, stop or restart of a process placed there is sent as the
protocol's request; a relaunch is applied there too; the launch's shutdown stops every
share and waits until each has ended.

A machine that cannot be reached, refuses the login, or lacks tuilaunch or the launch
file: every process placed there fails with one line naming the machine and why; the rest
runs. A link that drops leaves the share running (it is a session there): the coordinator
says so and connects again, backing off. A start or restart of a process placed on a machine
not reached now tries again at once: a machine that failed (off when the launch began, or
its share gone) has its share started anew, a link being made again is tried now, and the
request waits for that attempt (`MachinesCoordinator.reach`).
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import os
from collections.abc import Mapping
from typing import Any

from ...errors import LaunchError
from ...plan.machines import Placement
from ..events import (
    Event,
    Failed,
    Log,
    ProcessExited,
    Relaunched,
    Shutdown,
    Started,
)
from ..plugins import Plugin
from ..session.connection import Connection
from ..session.session_dir import SessionError, launch_stem
from ..supervisor.placed import UNKNOWN
from ..supervisor.supervisor import Supervisor
from ..vocabulary.request import Request
from ..vocabulary.requests import (
    Apply,
    ExternalEvent,
    Restart,
    ShareLines,
    ShutdownLaunch,
    Start,
    Stop,
    Subscribe,
)
from .remote import RemoteError, open_remote_connection, run_remote
from .share_link import Share
from .share_mirror import ShareMirror
from .share_requests import ShareRequests
from .share_side import ShareSide

SHARE_OPTION = "--share"
MACHINES_TEXT_OPTION = "--machines-text"
START_TIMEOUT = 120.0
"""An ssh login, a Python start and the share's own load and resolve of the file."""
SUBSCRIBE_TIMEOUT = 30.0
"""How long a new link waits for its share's subscription (answered at once)."""
END_TIMEOUT = 60.0
"""How long the launch's end waits for a share to stop its processes (they escalate to
SIGKILL well within it)."""


def share_session_name(base: str, machine: str) -> str:
    """The session name of `machine`'s share: the launch's, then the machine's."""
    return f"{base[:63 - min(len(machine), 30)]}-{machine[:30]}"


def share_arguments(command: list[str], arguments: Mapping[str, str], name: str,
                    placement: Placement, machine: str) -> list[str]:
    """The remote tuilaunch's words that start `machine`'s share. A launch file given by
    path is given by the same (absolute) path: it must exist at that path there; PACKAGE
    FILE is found in that machine's own ament index."""
    files = [os.path.abspath(command[0])] if len(command) == 1 else list(command)
    return ["--", *files, *(f"{k}:={v}" for k, v in arguments.items()), "--detach",
            "--name", name, SHARE_OPTION, machine, MACHINES_TEXT_OPTION, placement.text]


class MachinesCoordinator(Plugin):
    """The launching side's plugin: runs the other machines' shares and mirrors them."""

    def __init__(self, supervisor: Supervisor, placement: Placement, command: list[str],
                 arguments: Mapping[str, str], session_name: str | None = None,
                 environ: Mapping[str, str] | None = None) -> None:
        """`command` is FILE or PACKAGE FILE as given; `session_name` the launch's session
        here, if any (the shares' names start with it)."""
        self.supervisor = supervisor
        self.placement = placement
        self.command = list(command)
        self.arguments = dict(arguments)
        self.environ = dict(os.environ if environ is None else environ)
        base = session_name or f"{launch_stem(command[-1])}-{os.getpid()}"
        domain = self.environ.get("ROS_DOMAIN_ID")
        self.shares: dict[str, Share] = {}
        for machine in placement.used(supervisor.plan):
            if domain is not None:
                # the launching side's domain, unless the machines file sets one on purpose
                machine = dataclasses.replace(
                    machine, env={"ROS_DOMAIN_ID": domain, **machine.env})
            self.shares[machine.name] = Share(machine, share_session_name(base, machine.name))
        self.happened: dict[tuple[str, str], ExternalEvent] = {}
        """The last start and exit of each process, told to each share (again on connect:
        what a node there waits for may have happened before)."""
        self._tasks: set[asyncio.Task[Any]] = set()
        self._closing = False
        self.requests = ShareRequests(self.shares, lambda: supervisor.plan, self._spawn)
        """Their processes' commands, their keyboards (share_requests.py)."""
        self.mirror = ShareMirror(supervisor)
        """Their events, states and lines, shown here as local ones (share_mirror.py)."""
        supervisor.set_placement(None, self)
        supervisor.subscribe(self._on_event)

    # --- the run --------------------------------------------------------------------------

    def run_started(self) -> None:
        # tasks of our own: the supervisor cancels its tasks before plugins close, and a
        # share being started must be seen through to be stopped
        for share in self.shares.values():
            self._spawn(self._follow(share))

    def _spawn(self, coroutine: Any) -> None:
        task = asyncio.ensure_future(coroutine)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    async def _follow(self, share: Share) -> None:
        share.following = True
        try:
            await self._follow_share(share)
        finally:
            share.following = False
            share.tell(share.failure or f"{share.machine.name}: not connected")

    async def _follow_share(self, share: Share) -> None:
        try:
            await self._start(share)
        except RemoteError as exc:
            if "already running" not in str(exc):  # else: it runs there, from before
                self._fail_share(share, str(exc))
                return
        relink = share.relink
        relink.back()
        while not share.ended.is_set():
            if relink.down is not None:
                await relink.next_attempt()  # its backoff, cut short by `reach`
            try:
                await self._connect(share)
                relink.back()
                reason = await self._read(share)  # told once subscribed (_connect)
                if not share.ended.is_set():
                    self.mirror.lost(share, reason)
                relink.lost(f"link to {share.machine.name} lost", reason)
                new = True
            except (LaunchError, OSError) as exc:
                reason = str(exc) or f"{share.machine.name} did not answer"
                if "no running session named" in reason:
                    # reached, but its session is gone: stopped as asked, or killed there
                    if self._closing or self.supervisor.shutting_down:
                        share.ended.set()
                        return
                    self._fail_share(share, f"{share.machine.name}: its share (session "
                                     f"{share.session}) ended without being asked")
                    return
                if relink.down is None:  # the first link not made
                    relink.lost(f"{share.machine.name} not reached", reason)
                    new = True
                else:
                    new = relink.failed(reason)
            share.tell(reason)
            if share.ended.is_set():
                return
            if new:  # each new reason once: a machine off for an hour is one line
                self.supervisor.log(f"{share.machine.name}: {reason}; its share runs on "
                                    f"there; connecting again in {relink.delay:g} s", "WARN")

    async def reach(self, share: Share, process_id: str) -> bool:
        """A start or restart of `process_id` while its machine is not reached: tries it
        again now, said in the launch pane and on each of its processes. True when its
        share was started anew (its processes start with it); LaunchError saying why it
        could not be reached."""
        if self._closing or self.supervisor.shutting_down:
            raise LaunchError(f"{process_id} runs on {share.machine.name}: the launch is "
                              "stopping")
        name = share.machine.name
        fresh = not share.following
        waiter: asyncio.Future[str | None] = asyncio.get_running_loop().create_future()
        share.waiters.append(waiter)
        self.supervisor.log(f"{name}: connecting again... ({process_id} runs there)", "WARN")
        waiting = []  # the failed ones: failed again, with the new reason, if this fails too
        for proc in self.supervisor.plan.processes:
            if proc.machine == name and proc.enabled and \
                    self.supervisor.states.get(proc.id) in ("failed", "pending"):
                if self.supervisor.states.get(proc.id) == "failed":
                    waiting.append(proc.id)
                self.supervisor.mirror(Log(
                    proc.id, reason=f"{name}: connecting again...", level="WARN",
                    data={"detail": f"(connecting to {name} again...)"}), "pending")
        if fresh:
            share.failure = None
            share.ended = asyncio.Event()
            self._spawn(self._follow(share))
        else:
            share.relink.now()  # the next attempt now, not after its back-off
        outcome = await waiter
        if outcome is not None:
            # this attempt's end, whichever way it came (the share's start failed, or a
            # link that was up retries on its own): what it set waiting is failed again
            # before the answer, so a status asked next agrees with it
            for waited in waiting:
                if self.supervisor.states.get(waited) == "pending":
                    self.supervisor.mirror(Failed(waited, reason=outcome), "failed")
            raise LaunchError(f"{process_id} runs on {name}, tried again: {outcome}")
        if fresh and self.supervisor.plan.process(process_id).trigger is None:
            # its new share starts it: the answer says how that went, not "pending"
            for _ in range(int(START_TIMEOUT * 10)):
                if self.supervisor.states.get(process_id) != "pending" or share.ended.is_set():
                    break
                await asyncio.sleep(0.1)
        return fresh

    async def _start(self, share: Share) -> None:
        args = share_arguments(self.command, self.arguments, share.session, self.placement,
                               share.machine.name)
        loop = asyncio.get_running_loop()
        self.supervisor.log(f"{share.machine.name}: starting its share as session "
                            f"{share.session} on {share.machine.host}")
        await loop.run_in_executor(None, lambda: run_remote(
            share.machine, args, START_TIMEOUT, self.environ))

    def _fail_share(self, share: Share, reason: str) -> None:
        share.failure = reason
        share.ended.set()
        share.tell(reason)
        for proc in self.supervisor.plan.processes:
            if proc.machine == share.machine.name and proc.enabled and \
                    self.supervisor.states.get(proc.id) in ("pending", "running", UNKNOWN):
                self.supervisor.mirror(Failed(proc.id, reason=reason), "failed")

    async def _connect(self, share: Share) -> None:
        """Links to the share, tells it what happened here, and subscribes: what it did
        before (or while the link was down) is mirrored, its missed lines asked for."""
        share.link, conn = await open_remote_connection(
            share.machine, share.session, environ=self.environ)
        share.conn = conn
        try:
            for happened in list(self.happened.values()):
                conn.send(happened, reply=False)
            result = await conn.call(Subscribe(), SUBSCRIBE_TIMEOUT)
        except BaseException:
            await self._unlink(share)
            raise
        self.supervisor.log(f"{share.machine.name}: following session {share.session}")
        self.mirror.events(share, result.get("recent") or [], {}, result.get("states") or {})
        self.mirror.back(share)
        for request in self.mirror.missed_lines(share, result.get("offsets") or {}):
            self._spawn(self._backfill(share, conn, request))
        share.tell(None)  # reached, and its processes' states known here
        if self._closing or self.supervisor.shutting_down:  # stopped while it started
            await self._stop_share(share, "the launch ended")

    async def _read(self, share: Share) -> str:
        """Mirrors the share's messages until its link closes; why it closed. Replies
        reach their `ask` here (Connection.receive)."""
        conn = share.conn
        assert conn is not None
        while (message := await conn.receive()) is not None:
            kind = message.get("type")
            if kind == "events" and share.backfill:
                share.held.append(message)  # after the earlier lines, in order
            elif kind == "events":
                self.mirror.events(share, message.get("events") or [],
                                   message.get("states") or {})
            elif kind == "ended":
                share.ended.set()
                await self._unlink(share)
                return "ended"
        return await self._unlink(share)

    async def _unlink(self, share: Share) -> str:
        """The link is gone: what waited on it is told, the lines held shown; why it
        went (ssh's last words)."""
        conn, share.conn = share.conn, None
        link, share.link = share.link, None
        share.typing = None  # its keyboard there is given back with the link
        if conn is not None:
            conn.fail(f"lost the link to {share.machine.name}")
            conn.close()
        self._show_held(share)
        if link is None:
            return f"lost the link to {share.machine.host}"
        loop = asyncio.get_running_loop()
        reason = await loop.run_in_executor(None, link.lost_reason)
        await loop.run_in_executor(None, link.close)
        return reason

    async def _backfill(self, share: Share, conn: Connection, request: ShareLines) -> None:
        """The lines a process printed that the link missed, shown before the events that
        came after them (held meanwhile)."""
        try:
            result = await conn.ask(request)
        except SessionError:  # refused: its lines stay in its log file there
            result = None
        if share.conn is not conn:
            return  # the link went meanwhile: what was held is shown already
        if isinstance(result, dict):
            self.mirror.backfilled(share, request.process, result)
        share.backfill.discard(request.process)
        if not share.backfill:
            self._show_held(share)

    def _show_held(self, share: Share) -> None:
        share.backfill.clear()
        held, share.held = share.held, []
        for batch in held:
            self.mirror.events(share, batch.get("events") or [], batch.get("states") or {})

    # --- what happens here, and requests -----------------------------------------------------

    def _on_event(self, event: Event) -> None:
        if isinstance(event, (Started, ProcessExited)) and event.process is not None and \
                event.pid is not None:
            try:
                machine = self.supervisor.plan.process(event.process).machine
            except KeyError:
                return
            on = "start" if isinstance(event, Started) else "exit"
            happened = ExternalEvent(event.process, on, event.pid, event.code)
            self.happened[(event.process, on)] = happened
            for share in self.shares.values():
                if share.machine.name != machine and share.conn is not None:
                    self._spawn(self._tell(share, happened, reply=False))
        elif isinstance(event, Shutdown):
            for share in self.shares.values():
                self._spawn(self._stop_share(share, event.reason or "shutdown"))
        elif isinstance(event, Relaunched):
            arguments = dict(line.split(":=", 1) for line in event.lines if ":=" in line)
            self.arguments = arguments
            for share in self.shares.values():
                self._spawn(self._tell(share, Apply(arguments)))

    async def _tell(self, share: Share, request: Request[Any], reply: bool = True) -> None:
        """A request whose reply is passed over (`reply` False: none comes back)."""
        with contextlib.suppress(LaunchError, ConnectionError, OSError):
            await share.send(request, reply)

    async def forward(self, request: Start | Stop | Restart) -> None:
        process_id = request.process
        machine = self.supervisor.plan.process(process_id).machine
        share = self.shares.get(machine or "")
        if share is not None and share.conn is None and not isinstance(request, Stop):
            # its machine may be up by now (a computer that boots late): tried again
            fresh = await self.reach(share, process_id)
            if fresh and (isinstance(request, Start) or request == Restart(process_id)):
                return  # its share was started anew, and this process with it
        share = self.requests.connected(process_id)
        result = await share.ask(request, START_TIMEOUT)
        state = result.get("state") if isinstance(result, dict) else None
        if isinstance(state, str):
            # as it is there once done (its events may still be on their way)
            self.supervisor.states[process_id] = state

    async def _stop_share(self, share: Share, reason: str) -> None:
        """Asks the share to stop; its `ended` closes the link."""
        if share.conn is not None:
            await self._tell(share, ShutdownLaunch(reason))

    async def close(self) -> None:
        """The launch is over here: every share stops, and is waited for."""
        self._closing = True
        for share in self.shares.values():
            if not share.ended.is_set():
                await self._stop_share(share, "the launch ended")
        waits = [asyncio.ensure_future(s.ended.wait()) for s in self.shares.values()]
        if waits:
            _, pending = await asyncio.wait(waits, timeout=END_TIMEOUT)
            for wait in pending:
                wait.cancel()
        for share in self.shares.values():
            if not share.ended.is_set():
                self.supervisor.log(f"{share.machine.name}: its share did not end within "
                                    f"{END_TIMEOUT:g} s (tuilaunch stop "
                                    f"{share.machine.host}:{share.session})", "ERROR")
        for task in list(self._tasks):
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        for share in self.shares.values():
            if share.link is not None:  # one that did not end: its ssh ends here
                await self._unlink(share)
            for log in share.logs.values():
                log.close()


def placement_plugin(supervisor: Supervisor, placement: Placement | None, command: list[str],
                     arguments: Mapping[str, str], session_name: str | None = None,
                     ) -> Plugin | None:
    """The plugin a placed launch needs on this side, if any: a share's, or the
    coordinator when other machines run some of its processes."""
    if placement is None:
        return None
    if placement.share is not None:
        return ShareSide(supervisor, placement.share)
    if not placement.used(supervisor.plan):
        supervisor.set_placement(None, None)
        return None
    return MachinesCoordinator(supervisor, placement, command, arguments, session_name)


__all__ = ["MACHINES_TEXT_OPTION", "SHARE_OPTION", "MachinesCoordinator",
           "placement_plugin", "share_arguments", "share_session_name"]
