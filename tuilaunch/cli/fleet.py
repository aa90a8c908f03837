"""The session commands over several sessions and machines: `ls HOST [HOST ...]`, and
`status`, `stop`, `logs` of several sessions (`tuilaunch stop nuc:base arm:base`, or
`arm:` for every session on arm); and which form a command line is (`stop A B`: two
sessions, or a session and its process).

Each machine or session is asked in a thread of its own, so one slow or unreachable robot
costs its own time, not the sum; one that fails is one line on stderr naming it and why,
never a stop for the others, and the exit status says that something failed. The forms of
one session keep their output as it was (commands.py runs them).
"""

from __future__ import annotations

import argparse
import json
import sys
import threading
from collections.abc import Callable, Iterable, Sequence
from typing import Any, TextIO, TypeVar

from ..client.link import LOCAL, LinkLost, parse_session
from ..engine.errors import LaunchError
from ..engine.run.machines.proxy import list_sessions
from ..engine.run.machines.remote import check_host, list_remote
from ..engine.run.session import session_dir
from ..engine.run.session.session_dir import SessionError
from . import commands
from .commands import one_line
from .logs import show_logs
from .parsers import commands_parser
from .process_commands import cmd_start, stop_processes

FAILED = 2
"""The exit status when any machine or session failed (as a single one's error)."""

T = TypeVar("T")
R = TypeVar("R")


def main(argv: list[str]) -> int:
    """The session commands (commands.main's), with the forms over several sessions here."""
    options = commands_parser().parse_args(argv)
    return commands.run(options, route(options))


def route(options: argparse.Namespace) -> Callable[[argparse.Namespace], int] | None:
    """The handler of a form over several sessions or machines; None for commands.py's
    own, `options` then made what it expects (one `name` or None)."""
    command = options.command
    if command == "ls":
        return ls_hosts if options.host else None
    if command == "start":
        return cmd_start
    if command not in ("stop", "status", "logs", "attach"):
        return None
    words: list[str] = list(options.name)
    if command == "logs":
        options.process = None
        if len(words) > 1 and not is_session(words[-1]):
            options.process = words.pop()
    if command == "stop" and len(words) > 1 and not all(is_session(w) for w in words):
        # `stop NAME PROCESS ...`: processes of one session; a word that is neither is
        # said before anything stops (process_commands.py)
        options.name, options.process = words[0], words[1:]
        return stop_processes
    if len(words) > 1 or any(w.endswith(":") for w in words):
        options.name = words
        return {"stop": stop_many, "status": status_many, "logs": logs_many,
                "attach": attach_many}[command]
    options.name = str(parse_session(words[0])) if words else None
    return None


def is_session(word: str) -> bool:
    """Whether a word of `logs` names a session (else it is the process): an address with
    a host, or a session running here."""
    return ":" in word or word in session_dir.live_sessions(clean=False)


# --- in parallel ------------------------------------------------------------------------------

def in_parallel(work: Callable[[T], R], items: Sequence[T]) -> list[R | LaunchError]:
    """`work` of each item, each in a thread of its own, in the items' order; an item's
    LaunchError is its result. Daemon threads: Ctrl+C ends the command at once (a thread
    pool's workers would be waited for at exit, one stuck on a dead link for ever)."""
    results: list[R | LaunchError] = [SessionError("not asked")] * len(items)

    def one(index: int, item: T) -> None:
        try:
            results[index] = work(item)
        except LaunchError as exc:
            results[index] = exc
        except Exception as exc:  # a bug or an OS error: that item's line, not a traceback
            results[index] = SessionError(f"{exc.__class__.__name__}: {exc}")

    threads = [threading.Thread(target=one, args=(i, item), daemon=True,
                                name=f"fleet-{i}") for i, item in enumerate(items)]
    for thread in threads:
        thread.start()
    for thread in threads:
        while thread.is_alive():
            thread.join(0.2)  # wakes up for a KeyboardInterrupt
    return results


def say(command: str, exc: LaunchError) -> None:
    print(f"tuilaunch {command}: error: {one_line(exc)}", file=sys.stderr)


# --- addresses --------------------------------------------------------------------------------

def host_of(word: str) -> str | None:
    """`HOST:` (every session there): its host; `local:` is None, this computer."""
    host = word[:-1]
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]  # an IPv6 address
    return None if host == LOCAL else check_host(host, word)


def sessions_on(host: str | None) -> list[str]:
    """The addresses of every session on `host` (None: here), as a user writes them."""
    if host is None:
        return session_dir.live_sessions()
    label = f"[{host}]" if ":" in host else host
    return [f"{label}:{s['name']}" for s in list_remote(host)]


def expand(command: str, words: Iterable[str]) -> tuple[list[str], bool]:
    """Each word as session addresses, `HOST:` as every session there (the hosts asked in
    parallel), in order, each once; whether a word could not be (said on stderr)."""
    words = list(words)
    hosts = [w for w in words if w.endswith(":")]
    found = dict(zip(hosts, in_parallel(lambda w: sessions_on(host_of(w)), hosts),
                     strict=True))
    addresses: list[str] = []
    failed = False
    for word in words:
        if not word.endswith(":"):
            try:
                addresses.append(str(parse_session(word)))
            except LaunchError as exc:
                say(command, exc)
                failed = True
            continue
        result = found[word]
        if isinstance(result, LaunchError):
            say(command, result)
            failed = True
        elif not result:
            where = "here" if word == f"{LOCAL}:" else f"on {word[:-1]}"
            print(f"tuilaunch {command}: no running session {where}", file=sys.stderr)
        addresses += [] if isinstance(result, LaunchError) else result
    return list(dict.fromkeys(addresses)), failed


# --- ls HOST ... --------------------------------------------------------------------------------

def ls_hosts(options: argparse.Namespace) -> int:
    """`ls HOST [HOST ...]`: every session of those machines in one table (HOST first);
    a machine that cannot be asked is a line on stderr, the others are listed."""
    hosts = list(dict.fromkeys(options.host))

    def listing(host: str) -> list[dict[str, Any]]:
        rows = list_sessions() if host == LOCAL else list_remote(check_host(host))
        return [{**row, "host": host} for row in rows]

    rows: list[dict[str, Any]] = []
    failed = False
    for result in in_parallel(listing, hosts):
        if isinstance(result, LaunchError):
            say("ls", result)
            failed = True
        else:
            rows += result
    commands.print_sessions(rows, options.json, hosts=True)
    return FAILED if failed else 0


# --- status, stop --------------------------------------------------------------------------------

def status_many(options: argparse.Namespace) -> int:
    """Each session's status in the order given (asked in parallel); `--json`: a list, each
    with its `session` address."""
    addresses, failed = expand("status", options.name)
    results = in_parallel(lambda a: commands.session_status(a, resources=True), addresses)
    listed = []
    for address, result in zip(addresses, results, strict=True):
        if isinstance(result, LaunchError):
            say("status", result)
            failed = True
        elif options.json:
            listed.append({"session": address, **result.to_json()})
        else:
            commands.print_status(result, address)
    if options.json:
        print(json.dumps(listed, indent=2))
    return FAILED if failed else 0


def stop_many(options: argparse.Namespace) -> int:
    """Stops every session given at once (a robot slow to stop does not hold the others
    back); each says when it stopped, or why not."""
    addresses, failed = expand("stop", options.name)
    results = in_parallel(lambda a: commands.stop_session(a, f"tuilaunch stop: {a}: ",
                                                          quiet=options.json), addresses)
    listed = []
    for address, result in zip(addresses, results, strict=True):
        if isinstance(result, LaunchError):
            say("stop", result)
            failed = True
        else:
            listed.append({"session": address, "state": "stopped"})
    if options.json:
        print(json.dumps(listed, indent=2))
    return FAILED if failed else 0


# --- logs --------------------------------------------------------------------------------------

class LockedLines:
    """stdout shared by the sessions' threads: each write (whole lines) goes out alone."""

    def __init__(self, out: TextIO) -> None:
        self.out = out
        self.lock = threading.Lock()

    def write(self, text: str) -> int:
        with self.lock:
            return self.out.write(text)

    def flush(self) -> None:
        with self.lock:
            self.out.flush()

    def isatty(self) -> bool:
        return self.out.isatty()


def logs_many(options: argparse.Namespace) -> int:
    """The logs of several sessions, each line after its session's address; with `-f`, on
    while any of them runs, saying each that ends or whose link drops."""
    addresses, failed = expand("logs", options.name)
    out = LockedLines(sys.stdout)

    def follow(address: str) -> str | None:
        try:
            why = show_logs(options, address, out, tag=f"{address} ")
        except LinkLost as exc:  # the others go on; it failed
            why = exc.message
        except LaunchError as exc:
            say("logs", exc)  # at once: the others go on
            raise
        if options.follow:
            print(f"tuilaunch logs: {address}: " + ("the session ended" if why is None
                  else why), file=sys.stderr)
        return why

    if options.follow:
        results = in_parallel(follow, addresses)
    else:  # one session after the other: each one's lines together
        results = [in_parallel(follow, [a])[0] for a in addresses]
    # a session's error was said when it came; a link that dropped before its session
    # ended is a failure too
    failed = failed or any(isinstance(r, LaunchError | str) for r in results)
    return FAILED if failed else 0


# --- attach --------------------------------------------------------------------------------

def attach_many(options: argparse.Namespace) -> int:
    """One TUI over several sessions (tui/fleet/app.py). A `HOST:` that cannot be listed
    is a line here; a session whose machine cannot be reached is a root that retries."""
    from .commands import in_browser

    web = in_browser()  # a browser's tab (tuilaunch serve A B): the page is its terminal
    if not web and not (sys.stdin.isatty() and sys.stdout.isatty()):
        raise SessionError("attach needs a terminal",
                           hint=f"tuilaunch logs {' '.join(options.name)} -f")
    if options.type_into:
        raise SessionError("--type types into one session's process",
                           hint="attach one session with --type; over several, i on its row")
    addresses, failed = expand("attach", options.name)
    if not addresses:
        return FAILED
    from ..tui.fleet.app import FleetApp

    where = [parse_session(a) for a in addresses]
    app = FleetApp([(w.host, w.name) for w in where], scrollback=options.scrollback,
                   read_only=options.read_only)
    status = app.run() or 0
    if not web:  # a browser tab's stdout is the page's stream
        print(f"detached; the sessions run on: tuilaunch attach {' '.join(addresses)}")
    return FAILED if failed else int(status)
