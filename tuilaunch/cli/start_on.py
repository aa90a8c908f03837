"""`tuilaunch --on HOST FILE [name:=value ...]` (and `--on HOST PACKAGE FILE`): the launch
started on HOST as a session, over ssh, by the tuilaunch there (its file, packages and ROS
environment are HOST's, as `ssh HOST tuilaunch FILE --detach` would); then, without
`--detach`, this terminal's TUI attached to it (`tuilaunch attach HOST:NAME`), with
`--detach` the session's address printed."""

from __future__ import annotations

import argparse
import sys

from ..client.session_start import start_remote_session
from ..engine.errors import LaunchError

IGNORED = ("print_plan", "show_args", "headless", "machines")
"""Options that make no sense with --on (they read or run the file here): refused."""


def start_on(options: argparse.Namespace) -> int:
    host = options.on
    for option in IGNORED:
        if getattr(options, option, None):
            flag = "--" + option.replace("_plan", "").replace("_", "-")
            print(f"tuilaunch: error: {flag} is not taken with --on: run "
                  f"`ssh {host} tuilaunch ... {flag}` there", file=sys.stderr)
            return 2
    try:
        name = start_remote_session(host, list(options.items), options.name)
    except LaunchError as exc:
        print(f"tuilaunch: error: {exc}", file=sys.stderr)
        return 2
    label = f"[{host}]" if ":" in host else host
    address = f"{label}:{name}"
    if options.detach:
        print(address)
        return 0
    from .fleet import main as command_main

    return command_main(["attach", address])
