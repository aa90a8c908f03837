"""A node's terminal can host a debugger: gdb started through spawn runs a program to its
segfault and prints the signal and a backtrace into the node's output."""

from __future__ import annotations

import sys
from pathlib import Path

from .gdb_support import GDB, gdb_batch, requires_gdb
from .terminal_harness import PROGRAMS, start


@requires_gdb
async def test_gdb_in_a_node_terminal_shows_the_segfault_and_a_backtrace(
        tmp_path: Path, monkeypatch) -> None:
    # no network look-up of debug symbols, whatever the machine's gdb is set up to do
    monkeypatch.setenv("DEBUGINFOD_URLS", "")
    gdb = await start(tmp_path, gdb_batch(sys.executable, str(PROGRAMS / "segv.py")))
    try:
        await gdb.wait_for("about to crash")
        await gdb.wait_for("SIGSEGV")
        await gdb.wait_for("#0 ")  # the first frame of the backtrace
        await gdb.exit_code()  # -batch: gdb kills the program and quits after `bt`
    finally:
        gdb.kill()
    text = gdb.text()
    assert "Program received signal SIGSEGV" in text, text
    assert "#1 " in text, text  # a backtrace, not one line
    # the node's log file keeps the debugging session too
    assert b"Program received signal SIGSEGV" in gdb.running.log.path.read_bytes()


@requires_gdb
async def test_ctrl_c_typed_interrupts_a_program_under_interactive_gdb(
        tmp_path: Path, monkeypatch) -> None:
    # the terminal is gdb's controlling terminal: it hands it to the program, and a typed
    # ctrl+c stops the program into gdb's prompt, as in a terminal window
    monkeypatch.setenv("DEBUGINFOD_URLS", "")
    # what it prints is not in its command line, which gdb echoes at "Starting program"
    sleeper = "print('asleep', 'now', flush=True); import time; time.sleep(600)"
    gdb = await start(tmp_path, [GDB or "gdb", "-q", "-nx", "-ex", "set confirm off",
                                 "-ex", "set pagination off",
                                 "-ex", "run", "--args", sys.executable, "-c", sleeper],
                      controlling_terminal=True)
    try:
        await gdb.wait_for("asleep now")
        gdb.running.write_input(b"\x03")
        await gdb.wait_for("received signal SIGINT")
        gdb.running.write_input(b"bt\r")
        await gdb.wait_for("#1 ")
        gdb.running.write_input(b"quit\r")
        await gdb.exit_code()
    finally:
        gdb.kill()
