"""A launch as a background server: owns the Supervisor, serves clients on a unix socket.

`python -m tuilaunch.engine.server_main NAME FILE LOG_DIR ARGUMENTS_JSON` is started by
the command line in its own session (no terminal: a dropped ssh link never reaches it). The
TUI, `tuilaunch status/logs/wait/...` are clients. Each subscribed client has a bounded queue:
past its limit, output lines are dropped for that client only (with a count), and a client
that stops reading state changes altogether is disconnected, so a stalled or dead client
never holds up the supervisor. The log files keep every line; a client that subscribes late
gets, with the states, the log files' sizes at that instant, and reads what came before
from the files: nothing is missed and nothing is seen twice.
"""

from __future__ import annotations

import asyncio
import collections
import itertools
import os
import signal
import socket
import struct
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from ..describe.loader import set_command_line
from ..errors import LaunchError
from ..plan.session import Session
from . import session_dir
from .event_buffer import EventBuffer
from .events import Event
from .keyboard import Keyboard
from .log_reader import READ_LOG_LIMIT, read_log
from .plugins import Handler
from .protocol import MAX_MESSAGE, ProtocolError, decode, encode, event_to_dict
from .resource_watch import ResourceWatch, usage_fields
from .resources import Usage
from .supervisor import Supervisor

CLIENT_MAX_LINES = 20_000
"""Output lines queued per client before the oldest are dropped for that client."""
CLIENT_MAX_EVENTS = 10_000
"""State events queued for a client that reads nothing; past this it is disconnected."""
REACHABLE_CHECK = 1.0
"""Seconds between checks that the session's socket is still where clients look."""
RECENT_EVENTS = 2000
"""Non-output events kept for late clients (states' details and the launch pane)."""
BUILTIN_OPS = frozenset({"subscribe", "status", "start", "stop", "restart", "shutdown",
                         "apply", "kill", "run_action", "find", "read_log",
                         "watch_resources"})
"""Requests the server answers itself; plugins add others with `add_handler`."""


class ClientQueue:
    """One subscriber's bounded queue, drained by its own writer task."""

    def __init__(self, max_lines: int = CLIENT_MAX_LINES, interval: float = 0.0,
                 on_overflow: Callable[[], None] | None = None,
                 kinds: frozenset[str] | None = None, fair: bool = False) -> None:
        self.buffer = EventBuffer(max_lines=max_lines, fair=fair)
        self.kinds = kinds  # only these kinds of events (`tuilaunch echo` wants no output)
        self.on_overflow = on_overflow
        self.interval = interval  # a display asks for no more batches than it draws
        self.events = 0
        self.ready = asyncio.Event()
        self.overflowed = False

    def __call__(self, event: Event) -> None:
        if self.kinds is not None and event.kind not in self.kinds:
            return
        if event.kind != "output":
            self.events += 1
            if self.events > CLIENT_MAX_EVENTS and not self.overflowed:
                self.overflowed = True
                if self.on_overflow is not None:
                    self.on_overflow()  # its writer may be stuck; cut it loose now
        self.buffer(event)
        self.ready.set()

    def take(self) -> list[Event]:
        self.ready.clear()
        self.events = 0
        return self.buffer.drain()


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
        self._handlers: dict[str, Handler] = {}
        self._client_ids = itertools.count(1)
        self.clients: dict[int, ClientQueue] = {}  # subscribed clients' queues, by client id
        self.resources = ResourceWatch(self._running_pids, self.send)
        self.keyboard = Keyboard(self.supervisor, self.find_process)
        for op, handler in self.keyboard.handlers().items():
            self.add_handler(op, handler)
        for plugin in self.supervisor.plugins:
            for op, handler in plugin.handlers(self.find_process).items():
                self.add_handler(op, handler)
            plugin.serve(self)
        self.started = time.time()
        self.pids: dict[str, int] = {}
        self.details: dict[str, str] = {}
        self.recent: collections.deque[Event] = collections.deque(maxlen=RECENT_EVENTS)
        self.queues: set[ClientQueue] = set()
        self.writers: set[asyncio.StreamWriter] = set()
        self.apply_lock = asyncio.Lock()  # argument edits from several clients, one at a time
        self.dropped_clients = 0
        self.ended = False  # the supervisor's run is over; writers send "ended" and stop
        self.status_code = 0
        self._tasks: set[asyncio.Task[Any]] = set()
        self._server: asyncio.AbstractServer | None = None
        self._bound: tuple[int, int] | None = None  # the socket file we listen on
        self._bound_path: Path | None = None
        self._lock = -1  # the descriptor holding `<name>.lock`

    def add_handler(self, op: str, handler: Handler) -> None:
        """Answers the clients' requests `{"op": op, ...}` with `await handler(message)`.

        For requests the server does not know itself (a plugin's: lifecycle states, ROS
        inspection); a plugin pushes events to the clients with `supervisor.emit`."""
        if op in BUILTIN_OPS or op in self._handlers:
            raise ValueError(f"session request {op!r} is already answered")
        self._handlers[op] = handler

    @property
    def handlers(self) -> Mapping[str, Handler]:
        """The requests added with `add_handler`, by op."""
        return dict(self._handlers)

    # --- the supervisor's events -------------------------------------------------------------

    def _on_event(self, event: Event) -> None:
        if event.kind != "output":
            self.recent.append(event)
            if event.process is not None:
                if event.kind == "started" and event.pid is not None:
                    self.pids[event.process] = event.pid
                if event.reason is not None and event.kind != "log":
                    self.details[event.process] = event.reason
        for queue in list(self.queues):
            queue(event)

    def send(self, event: Event, client: int | None = None) -> None:
        """An event for one subscribed client (by id) or all, neither logged nor kept for
        late clients: the inspector's streams (run/plugins.py `Clients`)."""
        if client is None:
            for queue in list(self.queues):
                queue(event)
            return
        addressed = self.clients.get(client)
        if addressed is not None and addressed in self.queues:
            addressed(event)

    def subscribed(self, client: int) -> bool:
        queue = self.clients.get(client)
        return queue is not None and queue in self.queues

    def _running_pids(self) -> dict[str, int]:
        states = self.supervisor.states
        return {process: pid for process, pid in self.pids.items()
                if states.get(process) == "running"}

    def _client_gone(self, client: int) -> None:
        self.clients.pop(client, None)
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
                **self._placement_info()}

    def _placement_info(self) -> dict[str, Any]:
        """`--machines` as the launch was given it, so a client resolves the same plan."""
        placement = self.session.placement
        if placement is None:
            return {}
        return {"placement": {"text": placement.text, "path": placement.machines.path,
                              "share": placement.share}}

    def status(self, usage: Mapping[str, Usage] | None = None) -> dict[str, Any]:
        """Each process's state; with `usage` (ResourceWatch.current), its CPU%, resident
        memory and threads (None when it is not running)."""
        states = self.supervisor.states
        processes = []
        for proc in self.session.plan.processes:
            state = states.get(proc.id, "pending")
            fields = usage_fields((usage or {}).get(proc.id))
            del fields["growing"]  # a trend needs watching; status is one look
            processes.append({
                "id": proc.id, "name": proc.full_name or proc.label, "state": state,
                "pid": self.pids.get(proc.id) if state == "running" else None,
                "exit_code": self.supervisor.exit_codes.get(proc.id),
                "detail": self.details.get(proc.id), "machine": proc.machine, **fields,
                # the exact start (argv, paste-ready line, env changes); a crash's signal/core
                **self.supervisor.command_of(proc.id),
                **(self.supervisor.deaths.get(proc.id, {}) if state == "failed" else {})})
        counts: dict[str, int] = {}
        for proc in self.session.plan.processes:
            state = states.get(proc.id, "pending")
            counts[state] = counts.get(state, 0) + 1
        actions = [{"id": a.id, "kind": a.kind, "state": states.get(a.id, "pending")}
                   for a in self.session.plan.actions]
        return {**self.info(), "counts": counts, "processes": processes, "actions": actions,
                "dropped_clients": self.dropped_clients, "typing": self.keyboard.state()}

    # --- serving ---------------------------------------------------------------------------

    async def serve(self) -> int:
        self._lock = session_dir.claim(self.name)  # held until this process ends
        if session_dir.is_alive(self.name):
            os.close(self._lock)
            raise session_dir.SessionError(f"a session named {self.name} is already running",
                                           hint="choose another --name")
        await self._bind()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, self._signalled, sig)
        # no terminal: a SIGHUP can only come from someone who means it as "keep going"
        loop.add_signal_handler(signal.SIGHUP, lambda: None)
        keeper = asyncio.ensure_future(self._stay_reachable())
        try:
            status = await self.supervisor.run(keep_alive=True)
        finally:
            keeper.cancel()
            self.resources.close()
            if self._server is not None:
                self._server.close()
            if self._owns_name():  # never the files of a later session given our name
                session_dir.remove(self.name)
        self.status_code = status
        self.ended = True
        for queue in list(self.queues):
            queue.ready.set()  # writers flush what is left, then send "ended"
        if self._tasks:  # a client that stopped reading must not keep the server alive
            await asyncio.wait([*self._tasks], timeout=5.0)
        for writer in list(self.writers):
            writer.close()
        return status

    async def _bind(self) -> None:
        """Listens on the session's socket path (anew: the old socket, if any, is closed)."""
        if self._server is not None:
            self._server.close()
            self._server = None
        path = session_dir.socket_path(self.name)
        old = self._bound_path
        if old is not None and old.parent != path.parent and _identity_or_none(old) == self._bound:
            # the folder moved ($XDG_RUNTIME_DIR came back): no stale files left behind
            for suffix in (".sock", ".json", ".lock"):
                old.with_suffix(suffix).unlink(missing_ok=True)
        path.unlink(missing_ok=True)
        old_umask = os.umask(0o177)  # the socket is created 0600, never briefly wider
        try:
            self._server = await asyncio.start_unix_server(self._client, path=str(path),
                                                           limit=MAX_MESSAGE)
        finally:
            os.umask(old_umask)
        os.chmod(path, 0o600)
        self._bound = _identity(path)
        self._bound_path = path
        session_dir.write_info(self.name, self.info())

    def _owns_name(self) -> bool:
        try:
            lock_path = session_dir.session_root() / f"{self.name}.lock"
            return _identity(lock_path) == _identity_fd(self._lock)
        except (OSError, LaunchError):
            return False

    async def _stay_reachable(self) -> None:
        """Puts the session's files back when someone removed them: logind removes
        $XDG_RUNTIME_DIR when the user's last login ends (the ssh logout after --detach),
        a tmp cleaner or an `rm` removes a socket. Without this, the launch would run on
        with no way to attach, stop or even list it. One stat a second is the whole cost."""
        warned = False
        while True:
            await asyncio.sleep(REACHABLE_CHECK)
            try:
                if not self._owns_name():
                    try:
                        lock = session_dir.claim(self.name)
                    except session_dir.SessionError:
                        continue  # a newer session took the name; it keeps it
                    os.close(self._lock)
                    self._lock = lock
                if _identity_or_none(
                        session_dir.socket_path(self.name)) != self._bound:
                    await self._bind()
                    self._log(f"session {self.name}: its socket was removed; "
                              f"listening again at {session_dir.socket_path(self.name)}")
                warned = False
            except (OSError, LaunchError) as exc:
                if not warned:  # e.g. the folder cannot be made; try again, say it once
                    self._log(f"session {self.name}: cannot put its socket back: {exc}", "ERROR")
                    warned = True

    def _log(self, text: str, level: str = "WARN") -> None:
        self.supervisor.log(text, level)

    def _signalled(self, sig: signal.Signals) -> None:
        self._spawn(self.supervisor.shutdown(f"received {sig.name}"))

    def _spawn(self, coroutine: Any) -> asyncio.Task[Any]:
        task = asyncio.ensure_future(coroutine)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        sock = writer.get_extra_info("socket")
        if sock is not None and not _same_user(sock):
            writer.close()
            return
        self.writers.add(writer)
        lock = asyncio.Lock()
        queue: ClientQueue | None = None
        client = next(self._client_ids)
        try:
            await _send(writer, lock, {"type": "hello", "info": self.info()})
            while True:
                try:
                    line = await reader.readline()
                except (ValueError, ConnectionError):
                    return  # longer than MAX_MESSAGE, or the peer vanished
                if not line:
                    return
                try:
                    message = decode(line)
                except ProtocolError as exc:
                    await _send(writer, lock, {"type": "reply", "id": None, "ok": False,
                                               "error": str(exc)})
                    continue
                message["client"] = client  # set here: a client cannot speak for another
                if message.get("op") == "subscribe" and queue is None:
                    kinds = message.get("kinds")
                    queue = ClientQueue(
                        max(1, min(int(message.get("max_lines") or CLIENT_MAX_LINES),
                                   CLIENT_MAX_LINES)),
                        max(0.0, min(float(message.get("interval") or 0.0), 1.0)),
                        writer.transport.abort,
                        frozenset(map(str, kinds)) if isinstance(kinds, list) else None,
                        bool(message.get("fair")))
                    # states and file sizes at the same instant as the subscription: the
                    # client reads the files up to these sizes, then gets events from here
                    result: dict[str, Any] = {}
                    for plugin in self.supervisor.plugins:
                        result.update(plugin.snapshot())
                    result.update({"states": dict(self.supervisor.states),
                                   "offsets": self._log_sizes(),
                                   "recent": [event_to_dict(e) for e in self.recent],
                                   "arguments": self.session.arguments})
                    self.queues.add(queue)
                    self.clients[client] = queue
                    await _send(writer, lock, {"type": "reply", "id": message.get("id"),
                                               "ok": True, "result": result})
                    self._spawn(self._pump(queue, writer, lock))
                    continue
                self._spawn(self._answer(message, writer, lock))
        except (ConnectionError, OSError):
            return
        finally:
            self.keyboard.release(client)  # a client that is gone types no more
            if queue is not None:
                self.queues.discard(queue)
                queue.ready.set()
            self._client_gone(client)
            self.writers.discard(writer)
            writer.close()

    def _log_sizes(self) -> dict[str, int]:
        sizes = {}
        for proc in self.session.plan.processes:
            try:
                sizes[proc.id] = (self.log_dir / f"{proc.id}.log").stat().st_size
            except OSError:
                continue
        return sizes

    async def _pump(self, queue: ClientQueue, writer: asyncio.StreamWriter,
                    lock: asyncio.Lock) -> None:
        """Sends a client its queued events, one batch per round trip of the socket."""
        try:
            while queue in self.queues and not self.ended:
                await queue.ready.wait()
                if queue.overflowed:
                    self.dropped_clients += 1
                    break
                await self._send_events(queue, writer, lock)
                if queue.interval:
                    await asyncio.sleep(queue.interval)
            if self.ended:
                await self._send_events(queue, writer, lock)
                await _send(writer, lock, {"type": "ended", "status": self.status_code})
        except (ConnectionError, OSError):
            pass
        finally:
            self.queues.discard(queue)
            writer.close()

    async def _send_events(self, queue: ClientQueue, writer: asyncio.StreamWriter,
                           lock: asyncio.Lock) -> None:
        events = queue.take()
        if not events:
            return
        states = self.supervisor.states
        touched = {e.process: states[e.process] for e in events
                   if e.process is not None and e.process in states}
        await _send(writer, lock, {"type": "events", "states": touched,
                                   "events": [event_to_dict(e) for e in events]})

    async def _answer(self, message: dict[str, Any], writer: asyncio.StreamWriter,
                      lock: asyncio.Lock) -> None:
        request_id = message.get("id")
        try:
            result = await self._perform(message)
            reply = {"type": "reply", "id": request_id, "ok": True, "result": result}
        except (LaunchError, TypeError, ValueError) as exc:
            reply = {"type": "reply", "id": request_id, "ok": False, "error": str(exc)}
        except Exception as exc:  # one bad request must never take the session down
            reply = {"type": "reply", "id": request_id, "ok": False,
                     "error": f"{op_name(message)} failed: {type(exc).__name__}: {exc}"}
        try:
            await _send(writer, lock, reply)
        except (ConnectionError, OSError):
            pass  # the asker is gone; what it asked for was done all the same

    async def _perform(self, message: dict[str, Any]) -> Any:
        op = message.get("op")
        supervisor = self.supervisor
        if op == "status":
            # `ls` asks every session and needs no CPU figures: it can spare their 0.3 s
            wanted = message.get("resources", True) is not False
            return self.status(await self.resources.current() if wanted else None)
        if op == "watch_resources":
            self.resources.watch(int(message["client"]), bool(message.get("on", True)))
            return {}
        if op in ("start", "stop", "restart"):
            process = self.find_process(str(message.get("process")))
            if process not in {p.id for p in self.session.plan.processes}:
                raise LaunchError(f"{process} is an action, not a process: it cannot {op}")
            if op == "restart":
                await supervisor.restart(process, message.get("prefix") or None,
                                         message.get("log_level"))
            else:
                await getattr(supervisor, op)(process)
            return {"process": process, "state": supervisor.states.get(process)}
        if op == "shutdown":
            await supervisor.shutdown(str(message.get("reason") or "stop requested"))
            return {}
        if op == "apply":
            arguments = message.get("arguments")
            if not isinstance(arguments, dict):
                raise ValueError("apply needs arguments as an object")
            return await self.apply({str(k): str(v) for k, v in arguments.items()})
        if op == "kill":
            supervisor.kill_all()  # the impatient second `q`: SIGKILL whatever is left
            return {}
        if op == "run_action":
            run_action = getattr(supervisor, "run_action", None)
            if run_action is None:
                raise LaunchError("this supervisor cannot run an action again")
            await run_action(self.find_process(str(message.get("action"))))
            return {}
        if op == "find":
            return self.find_process(str(message.get("process")))
        if op == "read_log":
            # by id only: the file is the plan's own, never a path a client names
            process = self.find_process(str(message.get("process")))
            end = message.get("end")
            return read_log(self.log_dir / f"{process}.log", int(message.get("start") or 0),
                            None if end is None else int(end), int(message.get("skip") or 0),
                            int(message.get("limit", READ_LOG_LIMIT)),
                            bool(message.get("tail")))
        handler = self._handlers.get(str(op))
        if handler is not None:
            return await handler(message)
        raise ValueError(f"unknown request {op!r}")

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
        raise LaunchError(f"no process {ref!r}",
                          hint=f"processes: {', '.join(p.id for p in processes)}")

    async def apply(self, arguments: dict[str, str]) -> dict[str, Any]:
        async with self.apply_lock:
            running = {p for p, s in self.supervisor.states.items() if s == "running"}
            set_command_line(None, arguments)  # sys.argv as a file reads it, again
            preview = self.session.preview(arguments, running)
            if preview.error is not None or preview.plan is None:
                raise LaunchError(f"cannot apply: {preview.error}")
            plan = self.session.accept(preview)
            diff = await self.supervisor.replace_plan(plan)
            session_dir.write_info(self.name, self.info())
            self._emit_plan()
            return {"stop": diff.stop, "start": diff.start}

    def _emit_plan(self) -> None:
        # an event like the others, so it reaches every client in order with their states,
        # and the plugins (the machines' shares are relaunched with the same values)
        self.supervisor.emit(Event("relaunched", reason=None, lines=[
            f"{k}:={v}" for k, v in self.session.arguments.items()]))


def op_name(message: dict[str, Any]) -> str:
    return str(message.get("op"))


async def _send(writer: asyncio.StreamWriter, lock: asyncio.Lock, message: dict[str, Any]) -> None:
    async with lock:  # replies and event batches never interleave inside a line
        writer.write(encode(message))
        await writer.drain()


def _identity(path: Path) -> tuple[int, int]:
    info = os.stat(path)
    return info.st_dev, info.st_ino


def _identity_or_none(path: Path) -> tuple[int, int] | None:
    try:
        return _identity(path)
    except FileNotFoundError:
        return None


def _identity_fd(fd: int) -> tuple[int, int]:
    info = os.fstat(fd)
    return info.st_dev, info.st_ino


def _same_user(sock: socket.socket) -> bool:
    try:
        raw = sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, struct.calcsize("3i"))
    except (OSError, AttributeError):
        return False
    _, uid, _ = struct.unpack("3i", raw)
    return uid == os.getuid()
