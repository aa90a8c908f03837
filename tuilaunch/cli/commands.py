"""`tuilaunch ls | attach | stop | status | logs | restart | wait`: the session commands
(`logs` is in logs.py; the inspector's: topics, hz, echo, params, log-level, in
inspector.py).

Each is a short-lived client of a session server; all but `attach` work without a terminal,
so scripts and CI use them (`--json` where a script reads the answer). A session is named
`[HOST:]NAME`: with a HOST, the same protocol crosses an ssh link (engine/run/machines/remote.py).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..client.link import (
    ANSWER_TIMEOUT,
    LINK_LOST_STATUS,
    Link,
    LinkLost,
    open_link,
    parse_session,
    resolve_name,
)
from ..client.port import LaunchPort
from ..client.session_start import session_name_for as session_name_for
from ..client.session_start import start_session as start_session
from ..engine.errors import LaunchError
from ..engine.plan.machines import placement_from_text
from ..engine.run.events import LIVE_STATES
from ..engine.run.machines.remote import open_remote_link
from ..engine.run.session import session_dir
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary.requests import (
    Find,
    LifecycleState,
    Restart,
    ShutdownLaunch,
    Status,
    StatusReply,
    Subscribe,
)
from .inspect import inspector
from .logs import cmd_logs as cmd_logs  # found by name in main
from .parsers import COMMANDS as COMMANDS
from .parsers import LIFECYCLE_STATES, PROCESS_STATES, commands_parser

if TYPE_CHECKING:
    from ..tui.app import TuiLaunchApp


def main(argv: list[str], handler: Callable[[argparse.Namespace], int] | None = None) -> int:
    """`handler`: the command's, where it is not a cmd_NAME here or in inspector.py."""
    return run(commands_parser().parse_args(argv), handler)


def run(options: argparse.Namespace, handler: Callable[[argparse.Namespace], int] | None = None,
        ) -> int:
    """Runs `handler` (by default the command's cmd_NAME) with the command line's errors
    said in one line each (fleet.py passes the forms over several sessions)."""
    try:
        # cmd_NAME here (ls ... wait, logs, completion), or in inspector.py
        function = f"cmd_{options.command.replace('-', '_')}"
        handler = handler or globals().get(function) or getattr(inspector, function, None) \
            or _plot_command(function)
        return int(handler(options) or 0)
    except LinkLost as exc:
        # one line, and a status of its own: the session may well run on there
        print(f"tuilaunch {options.command}: {exc.message}", file=sys.stderr)
        return LINK_LOST_STATUS
    except LaunchError as exc:
        print(f"tuilaunch {options.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # `tuilaunch logs x | head`: the reader is gone, which is not an error of ours
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        # Ctrl+C on `logs -f`, `wait`, `echo`: said, never silence nor a traceback (hz and
        # echo say what they had first)
        print("tuilaunch: interrupted", file=sys.stderr)
        return 130


def _plot_command(function: str) -> Any:
    from .inspect import plot

    return getattr(plot, function)


# --- the end of a TUI client ------------------------------------------------------------

def report_end(app: TuiLaunchApp, name: str) -> None:
    """What the command line says after a TUI client closes."""
    supervisor = app.supervisor
    if app.detached:
        print(f"detached; session {name} runs on: tuilaunch attach {name}")
    elif app.signalled:
        print(f"tuilaunch: received {app.signalled}: every process of session {name} was "
              "stopped", file=sys.stderr)
    elif supervisor is None:
        print(f"tuilaunch: error: the TUI could not attach to session {name}, which runs on: "
              f"tuilaunch attach {name}, or tuilaunch stop {name}", file=sys.stderr)
    elif supervisor.killed_server:
        print(f"session {name} did not answer: its server was killed, and its watchdog "
              "killed every process of the launch", file=sys.stderr)
    elif supervisor.lost and app.session_host:
        print(f"tuilaunch: error: session {name} ended while the link was down (its "
              f"messages: session.log in {supervisor.log_dir} there)", file=sys.stderr)
    elif supervisor.lost:
        log = Path(supervisor.log_dir) / "session.log"
        print(f"tuilaunch: error: the server of session {name} ended unexpectedly (its "
              f"messages: {log})", file=sys.stderr)
    elif app.ended_elsewhere:
        print(f"session {name} was stopped elsewhere ({app.ended_elsewhere})", file=sys.stderr)
    if not app.detached and supervisor is not None:
        report_failures(supervisor)


def edited_since(file: str, read: Sequence[int] | None) -> bool:
    """The session's launch file was edited (or removed) since its plan was read from it
    (`read`: its stamp then, status's `file_stamp`): the TUI then draws the plan that runs,
    sent by the server, and its preview says what the edit would change."""
    from ..engine.plan.session import file_stamp

    now = file_stamp(file)
    return read is not None and (now is None or list(now) != list(read))


def report_failures(supervisor: LaunchPort) -> None:
    """What failed, left in the shell's scrollback as ros2 launch leaves it: each failed
    process with its exit code or signal and its log file, then the launch's log folder."""
    failed = [p for p, state in supervisor.states.items() if state == "failed"]
    for process in failed:
        reason = supervisor.reasons.get(process)
        print(f"tuilaunch: {process} failed{f' ({reason})' if reason else ''}; its output: "
              f"{supervisor.log_dir / f'{process}.log'}", file=sys.stderr)
    # a crash a respawn (or a restart) outlived still makes the exit status 1: say which
    earlier = [p for p in supervisor.crashed if p not in failed]
    for process in earlier:
        print(f"tuilaunch: {process} died during the run ({supervisor.crashed[process]}), "
              f"then ran again; its output: {supervisor.log_dir / f'{process}.log'}",
              file=sys.stderr)
    if failed or earlier:
        print(f"tuilaunch: every log of this launch: {supervisor.log_dir}", file=sys.stderr)


def one_line(exc: LaunchError) -> str:
    """An error in one line: its message, and its hint after a semicolon."""
    return f"{exc.message}; {exc.hint}" if exc.hint else exc.message


def argument_line(arguments: dict[str, str]) -> str:
    return " ".join(f"{k}:={v}" for k, v in arguments.items())


# --- commands ------------------------------------------------------------------------------

LS_ANSWER_TIMEOUT = 3.0  # `ls` asks every session in turn: a stopped one costs this, once


def session_status(name: str | None, answer_timeout: float = ANSWER_TIMEOUT,
            resources: bool = True) -> StatusReply:
    """`resources`: with each process's CPU, memory and threads (0.3 s more)."""
    link = open_link(name, answer_timeout=answer_timeout)
    try:
        return link.request(Status(resources=resources), short=True)
    finally:
        link.close()


def _silent_session(name: str, error: SessionError) -> dict[str, Any] | None:
    """An `ls` row for a session whose socket accepts but whose server does not answer,
    from the info it wrote when it started; None when it is gone."""
    info = session_dir.read_info(name)
    if info is None or not session_dir.pid_alive(int(info.get("pid") or 0)):
        return None
    return {"name": name, "file": info.get("file", "?"), "arguments": info.get("arguments", {}),
            "pid": info.get("pid"), "started": info.get("started", 0.0),
            "log_dir": info.get("log_dir", ""), "counts": {}, "answering": False,
            "problem": str(error)}


def cmd_ls(options: argparse.Namespace) -> int:
    """The sessions here (`ls HOST ...` is fleet.py's)."""
    return print_sessions(local_sessions(), options.json)


def local_sessions() -> list[dict[str, Any]]:
    """`ls`'s rows for this computer: each session's short status, asked in turn."""
    sessions: list[dict[str, Any]] = []
    for name in session_dir.live_sessions():
        try:
            sessions.append({**session_status(name, LS_ANSWER_TIMEOUT,
                                              resources=False).listing(), "answering": True})
        except SessionError as exc:
            # a stopped or stuck server is listed as such; one that ended meanwhile is not
            silent = _silent_session(name, exc)
            if silent is not None:
                sessions.append(silent)
    return sessions


def print_sessions(sessions: list[dict[str, Any]], as_json: bool,
                    hosts: bool = False) -> int:
    """The table (or JSON list) of `ls`; `hosts`: each row has a `host` (`ls HOST ...`),
    shown first."""
    if as_json:
        keys = ("name", "file", "arguments", "pid", "started", "log_dir", "counts",
                "answering") + (("host",) if hosts else ())
        print(json.dumps([{k: s[k] for k in keys} for s in sessions], indent=2))
        return 0
    if not sessions:
        print("no running sessions")
        return 0
    rows = [("HOST",) * hosts + ("NAME", "PID", "STARTED", "RUNNING", "FILE", "ARGUMENTS")]
    for s in sessions:
        total = sum(n for state, n in s["counts"].items() if state != "skipped")
        running = f"{s['counts'].get('running', 0)}/{total}" if s["answering"] else "?"
        rows.append(((s["host"],) if hosts else ()) + (
            s["name"], str(s["pid"]), _clock(s["started"]), running, s["file"],
            argument_line(s["arguments"])))
    _table(rows)
    for s in sessions:
        if not s["answering"]:
            problem = s.get("problem") or f"session {s['name']} does not answer"
            print(f"tuilaunch: {problem}", file=sys.stderr)
    return 0


def cmd_attach(options: argparse.Namespace) -> int:
    where = None if options.name is None else parse_session(options.name)
    host = None if where is None else where.host
    if where is None or where.host is None:
        # here, the session is found first; there, by connecting to it
        label = resolve_name(None if where is None else where.name)
    else:
        label = str(where)
    web = in_browser()
    if not web and not (sys.stdin.isatty() and sys.stdout.isatty()):
        raise SessionError("attach needs a terminal",
                           hint=f"tuilaunch logs {label} -f, or tuilaunch status {label}")
    remote = None
    typed = None
    if where is not None and where.host is not None:
        # one ssh login for both: the status first, then the TUI's subscription
        remote = open_remote_link(where.host, where.name)
        link = Link.connected(where.name, remote.sock, remote.hello, where.host)
        try:
            info = link.request(Status(resources=False), short=True)
            if options.type_into:  # a process that is not there: one line, no TUI
                typed = link.request(Find(process=options.type_into))
        except BaseException:
            link.release()  # the link's copy of the socket first: ssh ends once both close
            remote.close()
            raise
        link.release()
    else:
        info = session_status(label, resources=False)
        if options.type_into:
            here = open_link(label)
            try:
                typed = here.request(Find(process=options.type_into))
            finally:
                here.close()
    from ..engine.describe.python.loader import set_command_line
    from ..tui.app import make_app

    try:
        set_command_line(info.command or [info.file], info.arguments)
        placed = info.placement  # --machines: the same placement as the session's
        placement = placement_from_text(placed.text, placed.path, placed.share) \
            if placed else None
        app = make_app(info.file, info.arguments, Path(info.log_dir),
                       scrollback=options.scrollback, session_name=info.name,
                       session_host=host, remote_link=remote, placement=placement,
                       served=host is None and edited_since(info.file, info.file_stamp),
                       read_only=options.read_only)
        app.first_tab = options.tab
        app.first_typing = typed
        status = app.run() or 0
    finally:
        if remote is not None:
            remote.close()  # done already unless the TUI never took it
    if not web:  # a browser tab has no shell to tell: its stdout is the page's stream
        report_end(app, label)
    return status


WEB_DRIVER = "textual.drivers.web_driver:WebDriver"
"""The driver textual-serve (`tuilaunch serve`) runs each browser tab's TUI with: its
terminal is the page, reached through the pipes of the tab's process."""


def in_browser() -> bool:
    """This TUI is drawn in a browser tab by textual-serve (it names the driver in the
    environment): no terminal, and none needed."""
    return os.environ.get("TEXTUAL_DRIVER") == WEB_DRIVER


STOP_NOTICE = 3.0
"""After this many seconds, and as often again, `stop` says which processes it waits for."""


def cmd_stop(options: argparse.Namespace) -> int:
    name = stop_session(options.name, quiet=options.json)
    if options.json:
        print(json.dumps([{"session": name, "state": "stopped"}], indent=2))
    return 0


def stop_session(address: str | None, said: str = "tuilaunch stop: ",
                 quiet: bool = False) -> str:
    """Stops the session at `address` and waits for its end; says on stderr (after `said`)
    what it waits for. Its label once stopped (`quiet`: not said on stdout); a SessionError
    when it cannot be."""
    link = open_link(address, timeout=None)
    name = link.label
    pid = int(link.info["pid"]) if link.host is None else 0  # a pid there is not ours
    try:
        waiting = watch_ends(link)
        asking = link.send(ShutdownLaunch(reason="tuilaunch stop"))  # its reply comes at the end
        # the server closes its connections once every process is gone
        reply = await_stops(link, {asking: "shutdown"}, waiting, said, until_closed=True)
        if isinstance(reply.get(asking), str):
            raise SessionError(f"session {name}: {reply[asking]}")
    finally:
        link.close()
    deadline = time.monotonic() + 10
    while session_dir.pid_alive(pid) and time.monotonic() < deadline:
        time.sleep(0.02)
    if not quiet:
        print(f"session {name} stopped")
    return name


def watch_ends(link: Link) -> set[str]:
    """Subscribes to the processes' ends and the escalation's words (what `await_stops`
    reads); the processes that run now."""
    subscribed = link.request(Subscribe(max_lines=1, kinds=["exited", "failed", "log", "ended"]))
    return {p for p, state in (subscribed.get("states") or {}).items()
            if state in (*LIVE_STATES, "respawning")}


def await_stops(link: Link, asks: dict[int, str], waiting: set[str], said: str,
                until_closed: bool = False) -> dict[int, Any]:
    """Reads the link until each request of `asks` (its id: what it asks) has its reply
    (`until_closed`: until the server closes the connection), saying on stderr every
    STOP_NOTICE s which of `waiting` still run, and each escalation, as the TUI's countdown
    shows them. Each request's result, or its error's text."""
    replies: dict[int, Any] = {}
    asked = time.monotonic()
    notice = asked + STOP_NOTICE
    while until_closed or len(replies) < len(asks):
        try:
            message = link.receive_until(notice)
        except TimeoutError:
            if waiting:
                print(f"{said}waiting for {', '.join(sorted(waiting))} "
                      f"({time.monotonic() - asked:.0f} s)", file=sys.stderr)
            notice = time.monotonic() + STOP_NOTICE
            continue
        if message is None:
            lost = link.lost()
            if lost is not None:  # not stopped: only the link is gone
                raise lost
            if len(replies) < len(asks) and not until_closed:
                raise SessionError(f"session {link.label} ended before the stop was done")
            break
        if message.get("type") == "reply" and message.get("id") in asks:
            replies[message["id"]] = message.get("result") if message.get("ok") else \
                str(message.get("error"))
            if until_closed and isinstance(replies[message["id"]], str):
                break  # refused: nothing is stopping, no close is coming
        for event in message.get("events") or []:
            process = event.get("process")
            if event.get("kind") in ("exited", "failed"):
                waiting.discard(process)
            elif event.get("kind") == "log" and process in waiting and \
                    event.get("level") in ("WARN", "ERROR"):
                print(f"{said}{process}: {event.get('reason')}", file=sys.stderr)
    return replies


def cmd_status(options: argparse.Namespace) -> int:
    status = session_status(options.name)
    if options.json:
        print(json.dumps(status.to_json(), indent=2))
        return 0
    print_status(status)
    return 0


def print_status(status: StatusReply, label: str | None = None) -> None:
    """`status`'s text: the session (named `label` when given: HOST:NAME), then a row per
    process."""
    print(f"session {label or status.name}  pid {status.pid}  since "
          f"{_clock(status.started)}")
    print(f"  {status.file} {argument_line(status.arguments)}")
    print(f"  logs: {status.log_dir}")
    rows = [("PROCESS", "STATE", "PID", "CPU%", "RSS", "THREADS", "NODE", "")]
    for p in status.processes:
        cpu, rss, threads = p.cpu_percent, p.rss_bytes, p.threads
        where = f"@{p.machine}" if p.machine else ""  # placed on another machine
        rows.append((p.id + where, p.state, str(p.pid or ""),
                     "" if cpu is None else f"{cpu:.1f}",
                     "" if rss is None else _megabytes(rss),
                     "" if threads is None else str(threads), p.name or "",
                     p.detail if p.state != "running" and p.detail else ""))
    _table(rows, indent="  ")


def cmd_restart(options: argparse.Namespace) -> int:
    link = open_link(options.name, timeout=None)
    try:
        status = link.request(Status(resources=False), short=True)
        process = link.request(Find(process=options.process), short=True)
        found = status.process(process)
        machine = None if found is None else found.machine
        restart = Restart(process, options.prefix, options.log_level, options.terminal)
        if machine:
            result = _restart_placed(link, restart, machine)
        else:
            result = link.request(restart)
    finally:
        link.close()
    print(f"{result['process']}: {result['state']}")
    return 0 if result["state"] == "running" else 1


def _restart_placed(link: Link, restart: Restart, machine: str) -> dict[str, Any]:
    """A restart of a process another machine runs: what the launch says of reaching that
    machine meanwhile ("nuc: connecting again...") is printed as it comes, then the
    result."""
    link.request(Subscribe(max_lines=1, kinds=["log"]))
    asking = link.send(restart)
    reaching = False
    while True:
        message = link.receive()
        if message is None:
            raise link.lost() or SessionError(
                f"session {link.label} closed the connection during restart")
        if message.get("type") == "reply" and message.get("id") == asking:
            if not message.get("ok"):
                raise SessionError(f"session {link.label}: {message.get('error')}")
            result: dict[str, Any] = message["result"]
            return result
        for event in message.get("events") or []:
            reason = str(event.get("reason") or "")
            if event.get("kind") != "log" or event.get("process") is not None or \
                    not reason.startswith(f"{machine}: "):
                continue
            reaching = reaching or "connecting again" in reason
            if reaching:  # the lines of this attempt, not the machine's older news
                print(reason, file=sys.stderr, flush=True)


def cmd_wait(options: argparse.Namespace) -> int:
    state = options.state.lower()
    if state not in PROCESS_STATES + LIFECYCLE_STATES:
        raise SessionError(f"unknown state {options.state!r}",
                           hint=f"one of {', '.join(PROCESS_STATES + LIFECYCLE_STATES)}")
    deadline = None if options.timeout is None else time.monotonic() + options.timeout
    # a server that does not answer is said within the wait's own time (at least 1 s)
    answer = ANSWER_TIMEOUT if options.timeout is None else min(
        ANSWER_TIMEOUT, max(1.0, options.timeout))
    link = open_link(options.name, timeout=None, answer_timeout=answer)
    try:
        process = link.request(Find(process=options.process), short=True)
        if state in LIFECYCLE_STATES:
            return _wait_lifecycle(link, process, state, deadline)
        result = link.request(Subscribe())
        current = result["states"].get(process)
        last: dict[str, Any] = {"events": result.get("recent") or []}
        # stopped by a restart or a relaunch that starts it again: not an end to give up on
        again = process in (result.get("coming_back") or ()) or \
            _stopped_to_come_back(last, process, False)
        while current != state:
            if state in ("running", "respawning") and current in ENDED_STATES and not again:
                # it ended and nothing will start it again on its own: no wait forever
                print(f"tuilaunch wait: {process} {current}, not {state}"
                      f"{_ended_how(last, process)}: tuilaunch restart {link.label} "
                      f"{process} starts it again", file=sys.stderr)
                return 1
            if state == "exited" and current == "failed":
                # a crash ended it: not the end asked for, and that one will not come
                print(f"tuilaunch wait: {process} failed, not exited: "
                      f"{_death(last, process)}", file=sys.stderr)
                return 1
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                print(f"tuilaunch wait: {process} is {current}, not {state}, after "
                      f"{options.timeout:g} s", file=sys.stderr)
                return 1
            link.timeout = remaining
            try:
                message = link.receive()
            except TimeoutError:
                continue
            lost = link.lost() if message is None else None
            if lost is not None:  # the ssh link, not the session, ended: it may run on
                raise lost
            if message is None or message.get("type") == "ended":
                print(f"tuilaunch wait: the session ended with {process} {current}",
                      file=sys.stderr)
                return 1
            if message.get("type") == "events":
                current = (message.get("states") or {}).get(process, current)
                last = message
                again = _stopped_to_come_back(message, process, again)
        return 0
    finally:
        link.close()


ENDED_STATES = ("exited", "failed", "done", "cancelled", "skipped")
"""States a process leaves only when someone restarts it (a respawn is `respawning`)."""


def _stopped_to_come_back(message: dict[str, Any], process: str, before: bool) -> bool:
    """Whether the process's last end or start in the batch leaves it stopped by a restart
    or a relaunch (its `exited` event says `again`); `before` when the batch has neither.
    A process placed on another machine is restarted there: its end says it, though this
    side's subscription does not list it as coming back."""
    again = before
    for data in message.get("events") or []:
        if data.get("process") == process and data.get("kind") in ("exited", "failed",
                                                                    "started"):
            again = bool((data.get("data") or {}).get("again"))
    return again


def _ended_how(message: dict[str, Any], process: str) -> str:
    for data in reversed(message.get("events") or []):
        if data.get("process") == process and data.get("reason"):
            return f" ({data['reason']})"
    return ""


def _death(message: dict[str, Any], process: str) -> str:
    """How a process died, from the events of one batch."""
    for data in reversed(message.get("events") or []):
        if data.get("process") == process and data.get("reason"):
            return str(data["reason"])
    return "it died"


def _wait_lifecycle(link: Link, process: str, state: str, deadline: float | None) -> int:
    label = None
    while True:
        answer = link.request(LifecycleState(process=process))
        label = answer.get("state")
        if label == state:
            return 0
        if deadline is not None and time.monotonic() >= deadline:
            print(f"tuilaunch wait: {answer['node']} is {label or 'not answering'}, not "
                  f"{state}", file=sys.stderr)
            return 1
        time.sleep(0.2)


# --- helpers -------------------------------------------------------------------------------

def _megabytes(size: int) -> str:
    return f"{size / (1 << 20):.1f}M"


def _clock(stamp: float) -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(stamp))


def _table(rows: Sequence[tuple[str, ...]], indent: str = "") -> None:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    for row in rows:
        cells = [cell.ljust(width) for cell, width in zip(row, widths, strict=True)]
        print((indent + "  ".join(cells)).rstrip())


def cmd_serve(options: argparse.Namespace) -> int:
    from .serve.command import serve  # its web side is loaded only here

    return serve(options, local_sessions)


def cmd_completion(options: argparse.Namespace) -> int:
    from .completion import shell_code

    print(shell_code(options.shell), end="")
    return 0
