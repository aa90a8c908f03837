"""`tuilaunch serve`: the TUI in a web browser, through textual-serve.

`serve [HOST:]NAME` serves that session; `serve A B ...` or `serve nuc: arm:` serves the
fleet view of those sessions (tui/fleet/) at one URL; `serve FILE [name:=value ...]` (or
PACKAGE FILE) starts the launch as a detached session first, as `--detach` does, then
serves it; `serve` alone serves a page listing this machine's sessions, each opening its
TUI, and all of them together in the fleet view. The first line on stdout is the URL to
open. Each browser tab runs `tuilaunch attach NAME ...` (one more client of each session):
closing the tab, `q` in it, or stopping serve stops nothing.

Safe by default (serve_guard.py): loopback only unless `--host` says otherwise, and then a
token. `--read-only` makes every tab a view that changes nothing (client/read_only.py).
The web side (aiohttp, textual-serve) is serve_web.py, imported only once serving starts.
"""

from __future__ import annotations

import argparse
import asyncio
import errno
import os
import socket
import subprocess
import sys
from collections.abc import Callable
from typing import Any
from urllib.parse import quote, urlsplit

from ...client.link import resolve_name
from ...engine.errors import LaunchError
from ...engine.run.machines.remote import check_host, parse_address
from ...engine.run.session.session_dir import SessionError
from .guard import Guard

LAUNCH_SUFFIXES = (".py", ".xml", ".yaml", ".yml")


def serve(options: argparse.Namespace,
          local_sessions: Callable[[], list[dict[str, Any]]]) -> int:
    """`local_sessions`: this machine's sessions as `ls` lists them (commands.py), for the
    page that lists them."""
    guard = Guard.make(options.host, options.port, options.token_file, options.public_url)
    if options.public_url and urlsplit(options.public_url).scheme not in ("http", "https"):
        raise LaunchError(f"--public-url {options.public_url}: not an http:// or https:// URL")
    sessions, launch = _target(options.items)
    if options.name and launch is None:
        raise LaunchError("--name names the session a launch file starts: give FILE too")
    from ...engine.packages import ensure_environment

    ensure_environment()
    try:
        from . import web as serve_web
    except ImportError as exc:  # installed without its dependencies
        raise LaunchError(f"tuilaunch serve needs textual-serve ({exc})",
                          hint="pip install textual-serve") from None
    started: list[str] = []

    async def ready() -> None:
        """The port is ours: the launch starts (if asked), then the URL is said."""
        if launch is not None:
            name = await asyncio.get_running_loop().run_in_executor(
                None, start_detached, launch, options.name)
            started.append(name)
            app.sessions = [name]
        print(url_of(options, guard), flush=True)
        what = "the sessions of this machine" if not app.sessions else \
            f"session {app.sessions[0]}" if len(app.sessions) == 1 else \
            f"the fleet view of {' '.join(app.sessions)}"
        print(f"tuilaunch serve: serving {what}{' read-only' if options.read_only else ''}"
              f"; Ctrl+C stops serving, the launch runs on", file=sys.stderr, flush=True)

    app = serve_web.ServeApp(guard, sessions, options.read_only, local_sessions)
    try:
        asyncio.run(serve_web.serve_until_stopped(app, options.host, options.port, ready))
    except OSError as exc:
        if exc.errno == errno.EADDRINUSE:
            raise LaunchError(f"port {options.port} on {options.host} is in use",
                              hint="give another with --port") from None
        raise LaunchError(f"cannot listen on {options.host}:{options.port}: "
                          f"{exc.strerror or exc}") from None
    for name in started:
        print(f"tuilaunch serve: session {name} runs on: tuilaunch attach {name}, or "
              f"tuilaunch stop {name}", file=sys.stderr)
    return 0


def _target(items: list[str]) -> tuple[list[str], list[str] | None]:
    """(the sessions to serve, or the launch to start first: FILE or PACKAGE FILE and its
    name:=value); ([], None): the page of the sessions. Several sessions, or `HOST:` (every
    session there), are served as one fleet view."""
    if not items:
        return [], None
    if all(_is_session(word) for word in items):
        return [_session(word) for word in items], None
    return [], items


def _is_session(word: str) -> bool:
    """A session's address, not a launch file (or PACKAGE FILE, or name:=value)."""
    return ":=" not in word and not os.path.exists(word) and \
        not word.endswith(LAUNCH_SUFFIXES)


def _session(word: str) -> str:
    """A session as the tab's attach takes it; one line when it cannot be one."""
    if word.endswith(":"):  # every session on a host: listed by the tab's attach
        host = word[:-1].strip("[]")
        if host != "local":
            check_host(host, word)
        return word
    where = parse_address(word)
    if where.host is not None:
        return str(where)  # over ssh, checked by the tab's attach
    return resolve_name(where.name)  # a session here, or one line saying why not


def start_detached(items: list[str], name: str | None) -> str:
    """Starts the launch as `tuilaunch FILE ... --detach` does (the same checks and
    errors, said on stderr): the new session's name."""
    done = subprocess.run(
        [sys.executable, "-P", "-m", "tuilaunch", "--", *items, "--detach",
         *(["--name", name] if name else [])],
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, text=True)
    if done.returncode != 0:
        raise SessionError("the launch did not start (its error is above)")
    return done.stdout.strip().splitlines()[-1]


def url_of(options: argparse.Namespace, guard: Guard) -> str:
    """The URL to open: --public-url, else this machine's address as the browser would
    write it (its name when listening on every address); with the token when one is
    asked."""
    if options.public_url:
        base = options.public_url.rstrip("/") + "/"
    else:
        host = options.host
        if host in ("0.0.0.0", "::", ""):
            host = socket.gethostname()
        if ":" in host and not host.startswith("["):
            host = f"[{host}]"
        base = f"http://{host}:{options.port}/"
    return base + (f"?token={quote(guard.token, safe='')}" if guard.token else "")


__all__ = ["serve", "start_detached", "url_of"]
