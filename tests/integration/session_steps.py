"""A test's own steps around a session, taken from this process: the start a test only
needs as its setting, the stop that only ends it. Each is what the command does (the same
functions, the same server), without the command's own start, which costs half a second of
a loaded machine's time each; a test whose subject is `--detach` or `stop` runs the command.
"""

from __future__ import annotations

import os
import tempfile
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from tuilaunch.cli.commands import stop_session
from tuilaunch.client.session_start import start_session
from tuilaunch.engine.run.session.session_dir import SessionError


def start_here(path: str | Path, *args: str) -> str:
    """`tuilaunch PATH [--name NAME] [name:=value ...] --detach`, as the command starts it
    (start_session, a log folder of its own under ROS_LOG_DIR): the session's name, once it
    answers. The server is this process's child: a thread reaps it when it ends, so that
    it is never left a zombie that looks alive."""
    words = list(args)
    name = None
    if "--name" in words:
        at = words.index("--name")
        name = words[at + 1]
        del words[at:at + 2]
    assert all(":=" in word for word in words), f"not name:=value: {words}"
    arguments = dict(word.split(":=", 1) for word in words)
    base = Path(os.environ.get("ROS_LOG_DIR") or tempfile.gettempdir())
    base.mkdir(parents=True, exist_ok=True)
    # one folder per session: two started within a second by this process would share
    # the command's folder name (a stamp and the pid)
    log_dir = Path(tempfile.mkdtemp(prefix="tuilaunch-", dir=base))
    started, server = start_session(str(path), arguments, name, log_dir, [str(path)])
    threading.Thread(target=server.wait, daemon=True).start()
    return started


def stop_here(name: str, gone_ok: bool = False) -> None:
    """`tuilaunch stop NAME`: returns once the session and every process it started are
    gone (stop_session), said on this test's stderr. `gone_ok` (a fixture's end, as
    `stop` with its result unread): a session already gone (the test stopped it, or failed
    before) or one that cannot be reached is no error; the caller ends what is left. In a
    thread of its own: a Link runs its own event loop, and a test's may be running here."""
    with ThreadPoolExecutor(max_workers=1) as pool:
        try:
            pool.submit(stop_session, name, quiet=True).result()
        except (SessionError, OSError):
            if not gone_ok:
                raise
