"""A clean `tuilaunch stop` leaves no traceback anywhere: not in the session's own log
(session.log, the server's stderr), not in launch.log, not on the stop's or a following
client's terminal. The server used to leave every connection still open at its end to the
loop's close, which cancelled it, and Python 3.11's stream server logged that as
`Exception in callback StreamReaderProtocol.connection_made... Task cancelled`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from ..conftest import wait_for
from .test_sessions import runtime, start_detached, status, tl  # noqa: F401


@pytest.mark.parametrize("follower", [False, True], ids=["alone", "with-logs-f"])
def test_a_clean_stop_leaves_no_traceback_in_any_log(runtime, write, follower):  # noqa: F811
    name = start_detached(write)
    log_dir = Path(status(name)["log_dir"])
    follow = None
    if follower:  # a client still connected when the session ends
        follow = subprocess.Popen([sys.executable, "-m", "tuilaunch", "logs", "-f", name],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        wait_for(lambda: "tick" in (log_dir / "ticker-1.log").read_text())
    try:
        done = tl("stop", name)
        assert done.stdout.strip() == f"session {name} stopped"
        said = done.stderr
        if follow is not None:
            _, err = follow.communicate(timeout=60)
            said += err
    finally:
        if follow is not None and follow.poll() is None:
            follow.kill()
            follow.wait()
    logs = {path.name: path.read_text(errors="replace") for path in log_dir.iterdir()
            if path.suffix == ".log"}
    assert "session.log" in logs and "launch.log" in logs
    for where, text in [*logs.items(), ("the terminals", said)]:
        assert "Traceback" not in text and "Exception" not in text, f"{where}:\n{text}"
