"""The Services and Params tabs of a TUI attached to a session go through the session, as
the Topics tab does: the TUI calls a service and sets a parameter, and its process never
maps librcl nor rclpy (the session server, where the nodes run, does the ROS calls).

The shipped path: a session started with --detach, `tuilaunch attach` on a pseudo-terminal
driven by keys; what the keys did is read from the nodes' own log lines.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

from ..conftest import EXAMPLES, wait_for
from .session_steps import start_here, stop_here
from .test_sessions import Terminal, runtime, status, tl, wait_state  # noqa: F401

ESC, DOWN, TAB, CLEAR = "\x1b", "\x1b[B", "\t", "\x15"  # ctrl+u: the field emptied


def rcl_mapped(pid: int) -> list[str]:
    """The ROS client libraries in a process's memory (rclpy's binding, librcl)."""
    maps = Path(f"/proc/{pid}/maps").read_text()
    return sorted({line.rsplit("/", 1)[-1] for line in maps.splitlines()
                   if "librcl" in line or "_rclpy" in line})


def press(terminal: Terminal, keys: str, seen: bytes, again: bool = False,
          limit: float = 90.0) -> None:
    """Types `keys`, then waits for `seen` to be drawn. `again`: typed again every 10 s
    until then (a tab's key, harmless twice: pressed while the TUI still draws what it
    replays of the session, it may be read before the tabs are there)."""
    deadline = time.monotonic() + limit
    while True:
        mark = len(terminal.screen)
        os.write(terminal.master, keys.encode())
        retry = time.monotonic() + 10 if again else deadline
        while seen not in terminal.screen[mark:] and time.monotonic() < retry:
            terminal.pump(0.1)
        if seen in terminal.screen[mark:]:
            return
        assert time.monotonic() < deadline, f"{seen!r} never drawn: {terminal.screen[-800:]!r}"


def logged(name: str, process: str, text: str) -> bool:
    """Whether the process's log has `text`: read from its file, not with a logs command
    each look (the calls are the subject here, not the command)."""
    log = Path(status(name)["log_dir"]) / f"{process}.log"
    return log.exists() and text in log.read_text(errors="replace")


def test_services_and_params_of_an_attached_tui_load_no_rclpy(runtime):  # noqa: F811
    name = start_here(EXAMPLES / "bringup.py", "robot:=sg", "listener:=false")
    wait_state(name, "service_server-4", "running")
    tl("wait", name, "set_parameters-1", "done", "--timeout", "60")
    terminal = Terminal("attach", name)
    try:
        terminal.read_until(b"running")
        # Services: the list, then / and the name, enter picks it, the form's field
        press(terminal, "3", b"/sg/enable", again=True)
        press(terminal, "/sg/enable\r", b"SetBool")
        press(terminal, CLEAR + "true\r", b"enabled")
        wait_for(lambda: logged(name, "service_server-4", "enable called with data=True"),
                 what="the service call")
        # Params: the node, its parameters (the first row highlighted), the third is label
        press(terminal, ESC + "4", b"sg/control")
        press(terminal, "/sg/control\r", b"motors on")
        press(terminal, DOWN + DOWN, b"display name")
        press(terminal, TAB + CLEAR + "seamdemo\r", b"seamdemo")
        wait_for(lambda: logged(name, "configurable-3", "parameter label set to 'seamdemo'"),
                 what="the parameter set")
        assert rcl_mapped(terminal.proc.pid) == []
        # the session server did the calls: it has rclpy
        server = int(status(name)["pid"])
        assert rcl_mapped(server)
    finally:
        terminal.close()
    stop_here(name)
