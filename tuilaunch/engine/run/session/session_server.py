"""A launch as a background server: owns the Supervisor, serves clients on a unix socket.

`python -m tuilaunch.engine.server_main NAME FILE LOG_DIR ARGUMENTS_JSON` is started by
the command line in its own session (no terminal: a dropped ssh link never reaches it). The
TUI, `tuilaunch status/logs/wait/...` are clients. The log files keep every line; a client
that subscribes late gets, with the states, the log files' sizes at that instant, and reads
what came before from the files: nothing is missed and nothing is seen twice.

Here: the coordinator (status, the requests it answers, argument edits). The connections
and their bounded queues are in run/clients.py; the socket, lock and info files, kept
reachable, in run/session_socket.py.
"""

from __future__ import annotations

import asyncio
import collections
import os
import signal
import sys
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ...describe.python.loader import set_command_line
from ...errors import LaunchError
from ...plan.session import Session
from ..events import LIVE_STATES, Event, Log, Output, Relaunched, Started
from ..plugins import Handler
from ..supervisor.stopping import CTRL_C_REASON
from ..supervisor.supervisor import Supervisor
from ..vocabulary.forward import Forward
from ..vocabulary.request import Request, reply_to_json
from ..vocabulary.requests import (
    Apply,
    Find,
    Kill,
    PlanShown,
    ReadLog,
    ReadStamps,
    Restart,
    RunAction,
    SetView,
    ShutdownLaunch,
    Start,
    Status,
    Stop,
    Subscribe,
    WatchResources,
)
from ..vocabulary.status import ActionStatus, PlacementInfo, ProcessStatus, StatusReply, Typing
from . import session_dir
from .clients import CLIENT_MAX_EVENTS as CLIENT_MAX_EVENTS
from .clients import CLIENT_MAX_LINES as CLIENT_MAX_LINES
from .clients import ClientHub
from .clients import ClientQueue as ClientQueue
from .keyboard import Keyboard
from .launch_prints import LaunchPrints
from .log_reader import LAUNCH_LOG, READ_LOG_LIMIT, read_log
from .owner_gate import OwnerGate
from .protocol import event_to_dict, version_fields
from .resource_watch import ResourceWatch, usage_fields
from .resources import Usage
from .session_socket import REACHABLE_CHECK as REACHABLE_CHECK
from .session_socket import SessionSocket

RECENT_EVENTS = 2000
"""Non-output events kept for late clients (states' details and the launch pane)."""
BUILTIN_REQUESTS: frozenset[type[Request[Any]]] = frozenset({
    Subscribe, ReadStamps, SetView, Status, Start, Stop, Restart, ShutdownLaunch, Apply, Kill,
    RunAction, Find, ReadLog, WatchResources, PlanShown})
"""Requests the server answers itself; plugins add others with `add_handler`."""


class SessionServer:
    def __init__(self, name: str, session: Session, log_dir: Path,
                 sigterm_timeout: float = 5.0, sigkill_timeout: float = 5.0,
                 command: list[str] | None = None, supervisor: Supervisor | None = None) -> None:
        """`supervisor`: one made with its plugins (engine/launcher.py); a bare one without.
        The plugins' `handlers()` join the requests the server answers."""
        self.name = name
        self.command = command or [session.path]  # FILE or PACKAGE FILE, as the user gave
        self.session = session
        self.log_dir = log_dir
        self.supervisor = supervisor or Supervisor(
            session.plan, log_dir, sigterm_timeout=sigterm_timeout,
            sigkill_timeout=sigkill_timeout)
        self.supervisor.subscribe(self._on_event)
        self._handlers: dict[type[Request[Any]], Handler] = {}
        self.hub = ClientHub(self.info, self._snapshot, self._perform,
                             lambda: self.supervisor.states, self._client_gone,
                             self._log_sizes)
        self.socket = SessionSocket(name, self.hub.serve, self.info, self._log)
        self.resources = ResourceWatch(self._running_pids, self.send)
        self.keyboard = Keyboard(self.supervisor, self.find_process)
        for kind, handler in self.keyboard.handlers().items():
            self.add_handler(kind, handler)
        for plugin in self.supervisor.plugins:
            for kind, handler in plugin.handlers(self.find_process).items():
                self.add_handler(kind, handler)
            plugin.serve(self)
        self.started = time.time()
        self.pids: dict[str, int] = {}
        self.details: dict[str, str] = {}
        self.recent: collections.deque[Event] = collections.deque(maxlen=RECENT_EVENTS)
        self.partials: dict[tuple[str, str], Event] = {}
        """Each stream's unfinished line (a prompt waiting): a client that attaches now sees
        it too, as the log files hold only whole lines."""
        self.apply_lock = asyncio.Lock()  # argument edits from several clients, one at a time
        self.owner_gate = OwnerGate.from_environment()
        """Started by its owner's TUI: the processes wait for it to show the plan."""

    def add_handler(self, kind: type[Request[Any]], handler: Handler) -> None:
        """Answers the clients' requests of this class with `await handler(request,
        client)`.

        For requests the server does not know itself (a plugin's: lifecycle states, ROS
        inspection); a plugin pushes events to the clients with `supervisor.emit`."""
        if kind in BUILTIN_REQUESTS or kind in self._handlers:
            raise ValueError(f"session request {kind.op!r} is already answered")
        self._handlers[kind] = handler

    @property
    def handlers(self) -> Mapping[type[Request[Any]], Handler]:
        """The requests added with `add_handler`, by class."""
        return dict(self._handlers)

    clients = Forward[dict[int, ClientQueue]](
        "hub", doc="Subscribed clients' queues, by client id.")
    queues = Forward[set[ClientQueue]]("hub")
    writers = Forward[set[asyncio.StreamWriter]]("hub")
    dropped_clients = Forward[int]("hub", doc="Clients cut loose because they stopped reading.")
    ended = Forward[bool](
        "hub", doc="The supervisor's run is over; writers send `ended` and stop.")
    status_code = Forward[int]("hub")

    # --- the supervisor's events -------------------------------------------------------------

    def _on_event(self, event: Event) -> None:
        if isinstance(event, Output) and event.process is not None:
            key = (event.process, event.stream or "stdout")
            if event.data and "partial" in event.data:
                self.partials[key] = event
            elif event.lines:
                self.partials.pop(key, None)
        if not isinstance(event, Output):
            self.recent.append(event)
            if event.process is not None:
                if isinstance(event, Started) and event.pid is not None:
                    self.pids[event.process] = event.pid
                    # a restart or respawn: the last end's words are history now
                    self.details.pop(event.process, None)
                if event.reason is not None and not isinstance(event, Log):
                    self.details[event.process] = event.reason
                elif isinstance(event, Log) and (event.data or {}).get("detail") is not None:
                    # a row's detail said by a line (a machine being reached again, a lost
                    # link): `status` says it too while the process does not run
                    self._detail(event.process, str((event.data or {})["detail"]))
        self.hub.broadcast(event)

    def _detail(self, process: str, detail: str) -> None:
        if self.supervisor.states.get(process) in LIVE_STATES or not detail.strip("()"):
            self.details.pop(process, None)
        else:
            self.details[process] = detail.strip("()")

    def send(self, event: Event, client: int | None = None) -> None:
        """An event for one subscribed client (by id) or all, neither logged nor kept for
        late clients: the inspector's streams (run/plugins.py `Clients`)."""
        if client is None:
            self.hub.broadcast(event)
        else:
            self.hub.send(event, client)

    def subscribed(self, client: int) -> bool:
        return self.hub.subscribed(client)

    def _running_pids(self) -> dict[str, int]:
        states = self.supervisor.states
        return {process: pid for process, pid in self.pids.items()
                if states.get(process) in LIVE_STATES}

    def _client_gone(self, client: int) -> None:
        self.keyboard.release(client)  # a client that is gone types no more
        self.resources.forget(client)
        for plugin in self.supervisor.plugins:
            try:
                plugin.client_gone(client)
            except Exception as exc:  # a plugin's cleanup must never stop the server
                self._log(f"{type(plugin).__name__} failed to let client {client} go: {exc}")

    def info(self) -> dict[str, Any]:
        return {"name": self.name, "file": os.path.abspath(self.session.path),
                "command": self.command,
                "arguments": self.session.arguments, "pid": os.getpid(),
                "started": self.started, "log_dir": str(self.log_dir),
                # the launch file as the plan that runs was read from it (a client that
                # finds it edited since draws the server's plan, not the file's)
                "file_stamp": getattr(self.session, "stamp", None),
                # the protocol spoken: a client of another one says so and stops
                **version_fields(), **self._placement_info()}

    def _placement_info(self) -> dict[str, Any]:
        """`--machines` as the launch was given it, so a client resolves the same plan."""
        placement = self.session.placement
        if placement is None:
            return {}
        return {"placement": {"text": placement.text, "path": placement.machines.path,
                              "share": placement.share}}

    def status(self, usage: Mapping[str, Usage] | None = None,
               elsewhere: Mapping[str, dict[str, Any]] | None = None) -> StatusReply:
        """Each process's state; with `usage` (ResourceWatch.current), its CPU%, resident
        memory and threads (None when it is not running). `elsewhere`: how the processes
        placed on other machines were started, as those machines say (a terminal there is
        theirs to know: unknown, None, for one whose machine did not answer)."""
        states = self.supervisor.states
        placed = {p.id for p in self.session.plan.processes
                  if not self.supervisor.core.runs_here(p.id)} \
            if self.supervisor.core.placing.remote is not None else set()
        processes = []
        for proc in self.session.plan.processes:
            state = states.get(proc.id, "pending")
            # its `growing` is left out: a trend needs watching, status is one look
            fields = usage_fields((usage or {}).get(proc.id))
            # the exact start (argv, paste-ready line, env changes); a placed one's terminal
            # is its machine's to say
            started = self.supervisor.command_of(proc.id)
            if proc.id in placed:
                started = {**started, "terminal": None, **(elsewhere or {}).get(proc.id, {})}
            # a crash's signal and core
            death = self.supervisor.deaths.get(proc.id, {}) if state == "failed" else {}
            processes.append(ProcessStatus(
                id=proc.id, name=proc.full_name or proc.label, state=state,
                pid=self.pids.get(proc.id) if state in LIVE_STATES else None,
                # the last end's code, until the process starts again
                exit_code=None if state in (*LIVE_STATES, "pending") else
                self.supervisor.exit_codes.get(proc.id),
                detail=self.details.get(proc.id), machine=proc.machine,
                cpu_percent=fields["cpu_percent"], rss_bytes=fields["rss_bytes"],
                threads=fields["threads"], command=started.get("command"),
                command_line=started.get("command_line"), env=started.get("env"),
                unset_env=started.get("unset_env"), terminal=started.get("terminal"),
                signal=death.get("signal"), core=death.get("core")))
        counts: dict[str, int] = {}
        for proc in self.session.plan.processes:
            state = states.get(proc.id, "pending")
            counts[state] = counts.get(state, 0) + 1
        actions = [ActionStatus(id=a.id, kind=a.kind, state=states.get(a.id, "pending"))
                   for a in self.session.plan.actions]
        info = self.info()
        placement, stamp = info.get("placement"), info["file_stamp"]
        typing = self.keyboard.state()
        return StatusReply(
            name=info["name"], file=info["file"], command=info["command"],
            arguments=info["arguments"], pid=info["pid"], started=info["started"],
            log_dir=info["log_dir"], file_stamp=None if stamp is None else list(stamp),
            protocol=info.get("protocol"), tuilaunch=info.get("tuilaunch"),
            placement=None if placement is None else PlacementInfo(**placement),
            counts=counts, processes=processes, actions=actions,
            dropped_clients=self.dropped_clients,
            typing=None if typing is None else Typing(**typing))

    # --- serving ---------------------------------------------------------------------------

    async def serve(self) -> int:
        self.socket.claim()
        await self.socket.bind()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, self._signalled, sig)
        # no terminal: a SIGHUP can only come from someone who means it as "keep going"
        loop.add_signal_handler(signal.SIGHUP, lambda: None)
        keeper = asyncio.ensure_future(self.socket.stay_reachable())
        printed = sys.stdout
        sys.stdout = LaunchPrints(self.supervisor.log, printed, loop)
        try:
            await self.owner_gate.passed()  # the owner's tree drawn before the first start
            if self.owner_gate.timed_out:
                self._log(f"its owner did not show the plan within {self.owner_gate.wait:g} s: "
                          "the launch starts", "INFO")
            status = await self.supervisor.run(keep_alive=True)
        finally:
            sys.stdout = printed
            keeper.cancel()
            self.resources.close()
            self.socket.close()
        await self.hub.end(status)
        return status

    def _log(self, text: str, level: str = "WARN") -> None:
        self.supervisor.log(text, level)

    def _signalled(self, sig: signal.Signals) -> None:
        reason = CTRL_C_REASON if sig == signal.SIGINT else f"received {sig.name}"
        self.owner_gate.open()  # nothing starts after a stop: the run ends at once
        self.hub.spawn(self.supervisor.shutdown(reason))  # ros2 launch's words for SIGINT

    def _snapshot(self) -> dict[str, Any]:
        """What a client gets with its subscription: the plugins' snapshots, the states
        and the log files' sizes at that instant, the recent events, the arguments."""
        result: dict[str, Any] = {}
        for plugin in self.supervisor.plugins:
            result.update(plugin.snapshot())
        result.update({"states": dict(self.supervisor.states),
                       "offsets": self._log_sizes(),
                       "recent": [event_to_dict(e) for e in [*self.recent,
                                                             *self.partials.values()]],
                       "arguments": self.session.arguments})
        if self.supervisor.coming_back:  # stopped to start again (a restart, a relaunch)
            result["coming_back"] = sorted(self.supervisor.coming_back)
        return result

    def _log_sizes(self) -> dict[str, int]:
        sizes = {}
        for proc in self.session.plan.processes:
            try:
                sizes[proc.id] = (self.log_dir / f"{proc.id}.log").stat().st_size
            except OSError:
                continue
        return sizes

    async def _perform(self, request: Request[Any], client: int) -> Any:
        """One request's result, dispatched on its class; the plugins' by `add_handler`."""
        supervisor = self.supervisor
        match request:
            case Status(resources=wanted):
                # `ls` asks every session and needs no CPU figures: it can spare their 0.3 s
                usage, elsewhere = await asyncio.gather(
                    self.resources.current() if wanted else _nothing(),
                    self.supervisor.commands_elsewhere())
                return reply_to_json(self.status(usage, elsewhere))
            case WatchResources(on=on, processes=shown, trend=trend):
                self.resources.watch(client, on,
                                     None if shown is None else [str(p) for p in shown])
                if trend is None or not on:  # the processes whose last minutes it draws
                    return {}
                return {"history": self.resources.watch_trend(client,
                                                              [str(p) for p in trend])}
            case Start() | Stop() | Restart():
                process = self.find_process(request.process)
                if process not in {p.id for p in self.session.plan.processes}:
                    raise LaunchError(f"{process} is an action, not a process: it cannot "
                                      f"{request.op}")
                if isinstance(request, Restart):
                    await supervisor.restart(process, request.prefix or None,
                                             request.log_level, request.terminal)
                elif isinstance(request, Start):
                    await supervisor.start(process)
                else:
                    await supervisor.stop(process)
                return {"process": process, "state": supervisor.states.get(process)}
            case ShutdownLaunch(reason=reason):
                self.owner_gate.open()  # the owner left before it showed the plan
                await supervisor.shutdown(reason or "stop requested")
                return {}
            case PlanShown():
                self.owner_gate.open()
                return {}
            case Apply(arguments=arguments):
                return await self.apply({str(k): str(v) for k, v in arguments.items()})
            case Kill():
                supervisor.kill_all()  # the impatient second `q`: SIGKILL whatever is left
                return {}
            case RunAction(action=action):
                await supervisor.run_action(self.find_process(action))
                return {}
            case Find(process=process):
                return self.find_process(process)
            case ReadLog():
                # by id only: the file is the plan's own, never a path a client names;
                # LAUNCH_LOG is launch.log, the processes' starts and ends (`tuilaunch logs`)
                asked = request.process
                process = "launch" if asked == LAUNCH_LOG else self.find_process(asked)
                return read_log(self.log_dir / f"{process}.log", request.start, request.end,
                                request.skip,
                                READ_LOG_LIMIT if request.limit is None else request.limit,
                                request.tail)
        handler = self._handlers.get(type(request))
        if handler is not None:
            return await handler(request, client)
        raise ValueError(f"unknown request {request.op!r}")

    def find_process(self, ref: str) -> str:
        """A process by id (`talker-1`), full node name (`/r2/talker`) or unique node name."""
        processes = self.session.plan.processes
        for item_id in [*(p.id for p in processes), *(a.id for a in self.session.plan.actions)]:
            if ref == item_id:
                return item_id
        matches = [p.id for p in processes if ref in (p.full_name, p.name, p.label)
                   or (p.full_name or "").rsplit("/", 1)[-1] == ref]
        if len(matches) == 1:
            return matches[0]
        if matches:
            raise LaunchError(f"{ref!r} names several processes: {', '.join(matches)}",
                              hint="use a process id")
        for plugin in self.supervisor.plugins:
            # a node named in its own code, by the name it reported (the inspector learns it)
            named = getattr(plugin, "process_named", None)
            found = named(ref) if named is not None else None
            if found is not None:
                return str(found)
        raise LaunchError(f"no process {ref!r}",
                          hint=f"processes: {', '.join(p.id for p in processes)}")

    async def apply(self, arguments: dict[str, str]) -> dict[str, Any]:
        async with self.apply_lock:
            running = {p for p, s in self.supervisor.states.items() if s == "running"}
            set_command_line(None, arguments)  # sys.argv as a file reads it, again
            # the file is read again, as a new ros2 launch would: an edited file runs, and
            # one that no longer loads is refused while the launch runs on as it was
            preview = self.session.preview(arguments, running, reread=True)
            if preview.error is not None or preview.plan is None:
                raise LaunchError(f"cannot apply: {preview.error}")
            plan = self.session.accept(preview)
            diff = await self.supervisor.replace_plan(plan)
            session_dir.write_info(self.name, self.info())
            self._emit_plan(preview.edited)
            return {"stop": diff.stop, "start": diff.start}

    def _emit_plan(self, edited: str | None = None) -> None:
        # an event like the others, so it reaches every client in order with their states,
        # and the plugins (the machines' shares are relaunched with the same values);
        # `edited`: the file that changed on disk, for the other clients to be told
        self.supervisor.emit(Relaunched(reason=None, lines=[
            f"{k}:={v}" for k, v in self.session.arguments.items()],
            data={"edited": edited} if edited else None))


async def _nothing() -> None:
    return None

