"""`tuilaunch stop NAME PROCESS [PROCESS ...]` and `tuilaunch start NAME PROCESS [...]`:
some processes of one session stopped or started, the others and the session left as they
are (the TUI's `s` and `t`, supervisorctl's `stop`/`start`).

Every word is looked up before anything is done: a word that names neither a process of
the session nor a session stops nothing (`stop A B` of two sessions is fleet.py's, chosen
when every word names a session). The stops are asked at once and waited for together, so
one node slow to stop costs its own time; each end is said as it is told.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from ..client.link import Link, open_link
from ..engine.run.events import LIVE_STATES
from ..engine.run.session import session_dir
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary.requests import Find, Start, Status, StatusReply, Stop
from .commands import await_stops, one_line, watch_ends
from .suggest import close_matches, said_as_guess

RUNS = (*LIVE_STATES, "respawning")
"""The states a stop acts on (a respawn's wait is called off); any other is said as not
running."""


def stop_processes(options: argparse.Namespace) -> int:
    """`stop NAME PROCESS ...` (fleet.route chose this form)."""
    return _act(options, "stop")


def cmd_start(options: argparse.Namespace) -> int:
    return _act(options, "start")


def _act(options: argparse.Namespace, verb: str) -> int:
    address: str = options.name
    if address.endswith(":"):
        raise SessionError(f"{address} is every session on {address[:-1] or 'this computer'}: "
                           f"{verb} takes the processes of one session",
                           hint=f"tuilaunch {verb} HOST:NAME PROCESS ...")
    link = open_link(address, timeout=None)
    try:
        status = link.request(Status(resources=False), short=True)
        before = {p.id: p.state for p in status.processes}
        targets = list(dict.fromkeys(find(link, status, word, verb)
                                     for word in options.process))
        if verb == "start":
            skipped = [p for p in targets if before.get(p) == "skipped"]
            if skipped:  # the plan does not run it (the TUI's `t` leaves it too)
                raise SessionError(
                    f"{', '.join(skipped)} of session {link.label} "
                    f"{'is' if len(skipped) == 1 else 'are'} skipped by a condition: the "
                    "launch does not run it (a relaunch with values that enable it does); "
                    "nothing was started")
        results = _stop(link, targets) if verb == "stop" else _start(link, targets)
    finally:
        link.close()
    return _report(verb, targets, before, results, options.json)


def find(link: Link, status: StatusReply, word: str, verb: str) -> str:
    """The process id a word names in the session (an id, a full or unique node name, a
    node named by its own code as it reported itself); one line naming the word when it
    names none."""
    try:
        found = str(link.request(Find(process=word), short=True))
    except SessionError:
        if _names(status, word):
            raise  # it names several: the session's own line lists them
        found = ""
    if found in {p.id for p in status.processes}:
        return found
    if found:
        raise SessionError(f"{word} is an action of session {link.label}, not a process: "
                           "it is neither started nor stopped")
    if ":" in word or word in session_dir.live_sessions(clean=False):
        takes = "several sessions, or one session and its processes" if verb == "stop" \
            else "one session and its processes"
        raise SessionError(f"{word} is a session, not a process of session {link.label} "
                           f"({verb} takes {takes}): nothing was "
                           f"{'stopped' if verb == 'stop' else 'started'}")
    raise neither(word, link.label, status, verb)


def _names(status: StatusReply, word: str) -> bool:
    """Whether a word is a process's id, full node name or last part of it."""
    return any(word in (p.id, p.name, (p.name or "").rsplit("/", 1)[-1])
               for p in status.processes)


def neither(word: str, label: str, status: StatusReply, verb: str) -> SessionError:
    """A word that is no process of `label`'s, nor a session, in one line: the processes
    (by id) or sessions it resembles, else the processes there are."""
    ids = [p.id for p in status.processes]
    named = {p.id: p.id for p in status.processes}
    for p in status.processes:  # a node's full name, and its last part, say its id
        for name in (p.name or "", (p.name or "").rsplit("/", 1)[-1]):
            named.setdefault(name, p.id)
    named.update({s: s for s in session_dir.live_sessions(clean=False)})
    close = said_as_guess(list(dict.fromkeys(
        named[c] for c in close_matches(word, [n for n in named if n]))))
    return SessionError(f"{word!r} is neither a process of session {label} nor a session "
                        f"({close or 'processes: ' + ', '.join(ids)}): nothing was "
                        f"{'stopped' if verb == 'stop' else 'started'}")


def _stop(link: Link, targets: list[str]) -> dict[str, Any]:
    """Every stop asked at once, then waited for; each one's result (or error text)."""
    waiting = watch_ends(link) & set(targets)
    asks = {link.send(Stop(process=p)): p for p in targets}
    replies = await_stops(link, asks, waiting, f"tuilaunch stop: {link.label}: ")
    return {asks[i]: reply.replace("\n  hint: ", "; ") if isinstance(reply, str) else reply
            for i, reply in replies.items()}


def _start(link: Link, targets: list[str]) -> dict[str, Any]:
    results: dict[str, Any] = {}
    for process in targets:
        try:
            results[process] = link.request(Start(process=process))
        except SessionError as exc:  # the others are still started, and said
            results[process] = one_line(exc)
    return results


def _report(verb: str, targets: list[str], before: dict[str, str],
            results: dict[str, Any], as_json: bool) -> int:
    """Each process's outcome on stdout (a failure on stderr); 0 when each stop ended it
    or each start has it running, 1 otherwise (a start that failed), 2 for a refusal."""
    status = 0
    listed = []
    for process in targets:
        result = results.get(process)
        if isinstance(result, str):
            print(f"tuilaunch {verb}: error: {process}: {result}", file=sys.stderr)
            status = 2
            continue
        state = (result or {}).get("state") or "?"
        was = before.get(process)
        listed.append({"process": process, "state": state, "was": was})
        if as_json:
            continue
        if verb == "stop":
            print(f"{process} stopped" if was in RUNS else
                  f"{process} was not running ({was})")
        elif was in LIVE_STATES:
            print(f"{process} was running already")
        else:
            print(f"{process} started" if state == "running" else f"{process}: {state}")
        if verb == "start" and state in ("failed", "exited"):
            status = max(status, 1)  # it could not start, or ended at once
    if as_json:
        print(json.dumps(listed, indent=2))
    return status


__all__ = ["cmd_start", "stop_processes"]
