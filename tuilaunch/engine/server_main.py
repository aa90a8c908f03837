"""`python -m tuilaunch.engine.server_main NAME FILE LOG_DIR ARGUMENTS_JSON [COMMAND_JSON
[PLACEMENT_JSON]]`:
a launch as a background session server (run/session_server.py), with the ROS plugins.

Here, above `run` and `ros`, because the server's supervisor comes from the one factory
that wires the ROS plugins in (engine/launcher.py); `tuilaunch launch --detach` starts it.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from .run.lean_asyncio import asyncio_without_tls


def main(argv: list[str]) -> int:
    asyncio_without_tls()  # first: the modules below import asyncio
    import asyncio

    from .describe.python.loader import set_command_line
    from .errors import LaunchError
    from .launcher import make_supervisor
    from .packages import ensure_environment
    from .plan.session import Session
    from .ros.actions import exit_now_if_hung
    from .run.session.plan_ops import plan_handlers
    from .run.session.session_server import SessionServer

    name, path, log_dir, arguments_json = argv[:4]
    command = json.loads(argv[4]) if len(argv) > 4 else [path]
    arguments = json.loads(arguments_json)
    # `--machines`: {"text": the file's text, "path": where it was read, "share": MACHINE}
    placed = json.loads(argv[5]) if len(argv) > 5 else None
    ensure_environment()
    set_command_line(command, arguments)
    try:
        placement = None
        if placed:  # the machines' code, for a placed launch only
            from .plan.machines import placement_from_text

            placement = placement_from_text(placed["text"], placed["path"], placed.get("share"))
        session = Session(path, arguments, placement=placement)
    except LaunchError as exc:
        print(f"tuilaunch: error: {exc}", file=sys.stderr)
        return 2
    supervisor = make_supervisor(session.plan, Path(log_dir), placement=placement,
                                 command=command, arguments=arguments, session_name=name)
    server = SessionServer(name, session, Path(log_dir), command=command,
                           supervisor=supervisor)
    for kind, handler in plan_handlers(session).items():  # a client without the launch file
        server.add_handler(kind, handler)
    try:
        status = asyncio.run(server.serve())
    except LaunchError as exc:
        print(f"tuilaunch: error: {exc}", file=sys.stderr)
        return 2
    exit_now_if_hung(status)  # rclpy's shutdown hung: the DDS library's exit would too
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
