"""Tab completion for bash and zsh, through argcomplete (as ros2cli completes `ros2`).

`eval "$(tuilaunch completion bash)"` installs argcomplete's shell function; on each Tab
press the shell runs `tuilaunch` again with `_ARGCOMPLETE` set, and cli/__init__.py sends
it here before anything heavy is imported. What is completed:

- the first word: the session commands, package names, launch files and folders;
- after a package, its launch files (`*.launch.py`, `*_launch.xml`, ... in its share, as
  `ros2 launch PKG <TAB>`); after a file (or PACKAGE FILE), its arguments as `name:=`, and
  after `name:=`, the argument's choices (the file is loaded as `--show-args` loads it);
- session names for every session command, local ones and `HOST:` for each host of the
  ssh config, and after `HOST:`, that host's sessions (one ssh round trip, time-limited);
- process ids and node names (restart, wait, start, and after a session logs and stop;
  there the sessions and hosts too once the word typed starts one, as `logs A B` of several
  sessions is valid), topics (hz, echo), nodes (params, log-level), states (wait), log
  levels, shells.

A completion never prints into the user's shell: the shell code sends our stdout and stderr
to /dev/null (argcomplete writes the answer to fd 8), each completer swallows its own
failure, and a whole completion is cut off after DEADLINE seconds.
"""

from __future__ import annotations

import argparse
import os
import signal
from collections.abc import Callable, Iterable
from functools import partial
from typing import Any

from ..engine.run.vocabulary.request import Request
from ..engine.run.vocabulary.requests import Status, StatusReply, Topics
from .parsers import (
    COMMANDS,
    LEVELS,
    LIFECYCLE_STATES,
    NODE_LEVELS,
    PROCESS_STATES,
    commands_parser,
    launch_parser,
)

DEADLINE = 4.0
"""Seconds a whole completion may take before it gives up silently: the shell must never
hang on an unreachable host or a stuck session."""
REMOTE_TIMEOUT = 3.0
"""An ssh round trip for `HOST:<TAB>` (sessions there) or a session's processes there."""
SESSION_TIMEOUT = 1.5
"""A local session's answer (its processes, nodes, topics)."""
_OPTIONS_WITH_VALUE = {"--scrollback", "--name", "--machines", "--share", "--machines-text",
                       "--launch-prefix", "--launch-prefix-filter"}


def shell_code(shell: str) -> str:
    """What `eval "$(tuilaunch completion SHELL)"` runs: argcomplete's function for bash
    and zsh, registered for `tuilaunch`. No fallback to file names: a session name that
    matches nothing completes to nothing, not to a file of the current folder."""
    from argcomplete import shellcode

    return shellcode(["tuilaunch"], shell=shell, use_defaults=False)


def complete() -> None:
    """Answers one Tab press (COMP_LINE, COMP_POINT) and ends the process."""
    signal.signal(signal.SIGALRM, lambda *_: os._exit(1))
    signal.setitimer(signal.ITIMER_REAL, DEADLINE)
    try:
        import argcomplete

        line = os.environ.get("COMP_LINE", "")
        point = int(os.environ.get("COMP_POINT", len(line)))
        words = argcomplete.split_line(line, point)[3][1:]  # the words before the cursor
        if words and words[0] in COMMANDS and not os.path.exists(words[0]):
            parser = commands_parser()
            _attach_command_completers(parser)
        else:
            parser = launch_parser()
            launch_words = [w for w in words if w != "--"]
            items = next(a for a in parser._actions if a.dest == "items")
            items.completer = _guarded(  # type: ignore[attr-defined]
                lambda prefix, **_: launch_items(prefix, launch_words, first=not words))
        argcomplete.autocomplete(parser, default_completer=argcomplete.SuppressCompleter(),
                                 always_complete_options=False)
    except BaseException:
        pass
    os._exit(1)


def _guarded(completer: Callable[..., Iterable[str]]) -> Callable[..., list[str]]:
    """A completer whose failure (bad input, a session that ended, no ssh) completes to
    nothing."""
    def run(**kwargs: Any) -> list[str]:
        try:
            return list(completer(**kwargs))
        except Exception:
            return []
    return run


# --- the launcher: FILE | PACKAGE FILE | name:=value -----------------------------------------

def launch_items(prefix: str, words: list[str], first: bool) -> list[str]:
    """`words`: the words before the one being completed (options and their values
    included); `first`: the word is the command line's first."""
    positional = _positional(words)
    if ":=" in prefix:
        file = _launch_file(positional)
        return [] if file is None else argument_values(file, prefix, words)
    if not positional:
        found = path_candidates(prefix)
        if "/" not in prefix and not prefix.startswith((".", "~")):
            found += [p for p in sorted(package_names()) if p.startswith(prefix)]
            if first:
                found = [c for c in COMMANDS if c.startswith(prefix)] + found
        return found
    if len(positional) == 1 and not os.path.isfile(positional[0]):
        return [f for f in share_launch_files(positional[0]) if f.startswith(prefix)]
    file = _launch_file(positional)
    return [] if file is None else argument_names(file, prefix, words)


def _positional(words: list[str]) -> list[str]:
    """FILE or PACKAGE FILE: the words that are no option, option value nor name:=value."""
    found: list[str] = []
    skip = False
    for word in words:
        if skip:
            skip = False
        elif word.startswith("-"):
            skip = word in _OPTIONS_WITH_VALUE
        elif ":=" not in word:
            found.append(word)
    return found


def _launch_file(positional: list[str]) -> str | None:
    if len(positional) == 1 and os.path.isfile(positional[0]):
        return positional[0]
    if len(positional) == 2:
        from ..engine.packages import ensure_environment, find_launch_file_in_share

        ensure_environment()
        return str(find_launch_file_in_share(*positional))
    return None


def path_candidates(prefix: str) -> list[str]:
    """Folders (`name/`, completed without a space) and files that may be launch files."""
    from .suggest import LAUNCH_EXTENSIONS

    folder, _slash, start = prefix.rpartition("/")
    where = os.path.expanduser(folder + "/" if folder or prefix.startswith("/") else ".")
    found = []
    try:
        entries = list(os.scandir(where))
    except OSError:
        return []
    for entry in entries:
        if not entry.name.startswith(start) or (entry.name.startswith(".") and
                                                not start.startswith(".")):
            continue
        shown = f"{folder}/{entry.name}" if folder or prefix.startswith("/") else entry.name
        try:
            if entry.is_dir():
                found.append(shown + "/")
            elif entry.name.endswith(LAUNCH_EXTENSIONS):
                found.append(shown)
        except OSError:
            continue
    return sorted(found)


def package_names() -> list[str]:
    from ..engine.packages import ensure_environment, known_packages

    ensure_environment()
    return list(known_packages())


def share_launch_files(package: str) -> list[str]:
    """The launch files below a package's share, by name (what PACKAGE FILE takes)."""
    from ..engine.packages import ensure_environment
    from .suggest import launch_files

    ensure_environment()
    return launch_files(package)


def _declared(file: str, words: list[str]) -> list[Any]:
    """The file's arguments, loaded as `--show-args` loads it, with the values given so far
    (an include that needs one is followed)."""
    from ..engine.describe.python.loader import load_file, set_command_line
    from ..engine.packages import ensure_environment
    from ..engine.plan.resolve import declared_arguments

    ensure_environment()
    given = dict(w.split(":=", 1) for w in words if ":=" in w and not w.startswith(":="))
    set_command_line(_positional(words), given)
    found, _stopped = declared_arguments(load_file(file), given)
    return found


def argument_names(file: str, prefix: str, words: list[str]) -> list[str]:
    given = {w.split(":=", 1)[0] for w in words if ":=" in w}
    return [f"{a.name}:=" for a in _declared(file, words)
            if a.name.startswith(prefix) and a.name not in given]


def argument_values(file: str, prefix: str, words: list[str]) -> list[str]:
    name, _, start = prefix.partition(":=")
    for argument in _declared(file, words):
        if argument.name == name:
            choices = list(argument.choices or [])
            if not choices and argument.type == "bool":
                choices = ["true", "false"]
            return [f"{name}:={c}" for c in choices if str(c).startswith(start)]
    return []


# --- the session commands --------------------------------------------------------------------

def _attach_command_completers(parser: argparse.ArgumentParser) -> None:
    """Each sub-command's positionals, completed by their names (parsers.py names them)."""
    by_dest: dict[str, Callable[..., Iterable[str]]] = {
        "name": session_names, "process": processes, "node": nodes, "topic": topics,
        "state": lambda prefix, **_: _starting(PROCESS_STATES + LIFECYCLE_STATES, prefix),
        "host": lambda prefix, **_: _starting(["local", *ssh_hosts()], prefix),
    }
    for action in parser._actions:
        if not isinstance(action, argparse._SubParsersAction):
            continue
        for command, sub in action.choices.items():
            for sub_action in sub._actions:
                completer = by_dest.get(sub_action.dest)
                if command in ("logs", "stop") and sub_action.dest == "name":
                    # a session, then its processes (the last word of logs, the rest of stop)
                    completer = partial(sessions_or_processes, several=command == "stop")
                if command == "log-level" and sub_action.dest == "level":
                    completer = _choice(NODE_LEVELS)
                elif sub_action.dest == "log_level":
                    completer = _choice(tuple(level.lower() for level in LEVELS))
                elif sub_action.dest in ("load", "token_file"):
                    completer = _files
                elif command == "serve" and sub_action.dest == "items":
                    completer = _serve_items
                elif sub_action.option_strings and completer is not None:
                    completer = None  # an option's value named like a positional (--node)
                    if sub_action.dest == "node":
                        completer = nodes
                if completer is not None:
                    sub_action.completer = _guarded(completer)


def _serve_items(prefix: str, **_: Any) -> list[str]:
    """`serve`'s word: a session, or a launch file to start and serve."""
    return session_names(prefix) + path_candidates(prefix)


def _choice(values: Iterable[str]) -> Callable[..., list[str]]:
    return lambda prefix, **_: _starting(values, prefix)


def _starting(values: Iterable[str], prefix: str) -> list[str]:
    return [v for v in values if v.startswith(prefix)]


def _files(prefix: str, **_: Any) -> list[str]:
    folder, _slash, start = prefix.rpartition("/")
    where = os.path.expanduser(folder or ".")
    found = []
    for entry in os.scandir(where):
        if entry.name.startswith(start) and not (entry.name.startswith(".") and
                                                 not start.startswith(".")):
            shown = f"{folder}/{entry.name}" if folder else entry.name
            found.append(shown + "/" if entry.is_dir() else shown)
    return sorted(found)


def session_names(prefix: str, **_: Any) -> list[str]:
    """The sessions here and `HOST:` for each host of the ssh config; after `HOST:`, that
    host's sessions (its tuilaunch lists them over ssh)."""
    if ":" in prefix:
        host = prefix.rsplit(":", 1)[0]
        from ..engine.run.machines.remote import check_host, list_remote

        sessions = list_remote(check_host(host.strip("[]")), timeout=REMOTE_TIMEOUT)
        return [f"{host}:{s['name']}" for s in sessions
                if f"{host}:{s['name']}".startswith(prefix)]
    from ..engine.run.session import session_dir

    here = [n for n in session_dir.live_sessions(clean=False) if n.startswith(prefix)]
    return here + [f"{h}:" for h in ssh_hosts() if h.startswith(prefix)]


def sessions_or_processes(prefix: str, parsed_args: argparse.Namespace, several: bool,
                          **kwargs: Any) -> list[str]:
    """`logs` and `stop`: sessions (and hosts); after one session, its processes, and the
    sessions and hosts the typed prefix starts (`logs A B` of several sessions is valid
    too: `logs base robot2<Tab>` is `robot2:`); after several, more sessions (the form
    over a fleet; `logs A B PROCESS` too: the first one's processes); after a process,
    `several` (stop) more of them, else nothing."""
    from ..engine.run.session import session_dir

    given = list(getattr(parsed_args, "name", None) or [])
    if not given or ":" in prefix:  # the first word, or a HOST:NAME being typed
        return session_names(prefix)
    here = session_dir.live_sessions(clean=False)
    sessions = [word for word in given if ":" in word or word in here]
    if given[0] not in sessions:
        return []  # no session to ask
    if len(sessions) < len(given):  # a process given: the first word is the session
        return processes(prefix, parsed_args) if several else []  # logs takes one
    if len(sessions) > 1 and several:
        return session_names(prefix)  # stop A B PROCESS is no form: sessions alone
    try:
        found = processes(prefix, parsed_args)
    except Exception:
        found = []  # gone, or its host unreachable: the sessions still are offered
    if prefix or not found or len(sessions) > 1:
        # a bare Tab after one session offers its processes alone, not every host
        found += session_names(prefix)
    return found


def ssh_hosts() -> list[str]:
    """The hosts named in the ssh config (its `Host` lines, without patterns): the one in
    TUILAUNCH_SSH_COMMAND's `-F FILE`, else ~/.ssh/config."""
    from ..engine.run.machines.remote import ssh_command

    words = ssh_command()
    config = "~/.ssh/config"
    for i, word in enumerate(words):
        if word == "-F" and i + 1 < len(words):
            config = words[i + 1]
        elif word.startswith("-F") and len(word) > 2:
            config = word[2:]
    try:
        with open(os.path.expanduser(config), errors="replace") as file:
            lines = file.read().splitlines()
    except OSError:
        return []
    hosts: list[str] = []
    for line in lines:
        key, _, value = line.strip().replace("=", " ", 1).partition(" ")
        if key.lower() != "host":
            continue
        hosts += [h for h in value.split() if not any(c in h for c in "*?!")]
    return list(dict.fromkeys(hosts))


def _ask(parsed_args: argparse.Namespace, request: Request[Any],
         wait: float | None = None) -> Any:
    """One request to the session named on the line (a host's over ssh), time-limited."""
    from ..client.link import open_link

    address = getattr(parsed_args, "name", None)
    if isinstance(address, list):  # stop, status, logs take several: the first one's
        address = address[0] if address else None
    remote = address is not None and ":" in address
    wait = wait or (REMOTE_TIMEOUT if remote else SESSION_TIMEOUT)
    link = open_link(address, timeout=wait, answer_timeout=wait)
    try:
        return link.request(request, short=True)
    finally:
        link.close()


def processes(prefix: str, parsed_args: argparse.Namespace, **_: Any) -> list[str]:
    status: StatusReply = _ask(parsed_args, Status(resources=False))
    found = []
    for process in status.processes:
        found.append(process.id)
        if process.name:
            found.append(process.name)
    return _starting(dict.fromkeys(found), prefix)


def nodes(prefix: str, parsed_args: argparse.Namespace, **_: Any) -> list[str]:
    """Node names first (what ros2 param takes); a process id also names its node."""
    status: StatusReply = _ask(parsed_args, Status(resources=False))
    named = [p.name for p in status.processes if p.name]
    ids = [p.id for p in status.processes if p.name]
    return _starting(dict.fromkeys(named + ids), prefix)


def topics(prefix: str, parsed_args: argparse.Namespace, **_: Any) -> list[str]:
    # the session's first `topics` makes its ROS node and waits for discovery: more time
    graph = _ask(parsed_args, Topics(), wait=REMOTE_TIMEOUT)
    return _starting((t["name"] for t in graph["topics"]), prefix)


__all__ = ["complete", "shell_code"]
