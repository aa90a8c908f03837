"""A node's stdin is its own terminal: lines and raw keys typed into it arrive, ctrl+c is
SIGINT for a line reader and a key for a raw reader, and a node that reads nothing never
holds the launcher up."""

from __future__ import annotations

import asyncio
import signal
import time
from pathlib import Path

import pytest

from tuilaunch.engine.run.process.terminal_input import LIMIT, InputRefused

from .terminal_harness import Terminal, program, start


@pytest.fixture
async def terminals():
    started: list[Terminal] = []
    yield started
    for terminal in started:
        terminal.kill()


async def test_line_reader_gets_typed_lines_and_the_echo_shows_them(tmp_path: Path,
                                                                    terminals) -> None:
    reader = await start(tmp_path, program("line_reader.py"))
    terminals.append(reader)
    await reader.wait_for("ready")
    assert reader.running.write_input(b"hello robot\r") == 0  # Enter sends \r, as a terminal
    await reader.wait_for("got: hello robot")
    # the terminal echoes what is typed, as a terminal window shows it
    assert "hello robot" in reader.text("stdout").replace("got: hello robot", "")
    reader.running.write_input(b"\x04")  # ctrl+d: end of input
    assert await reader.exit_code() == 0
    assert "end of input" in reader.text()
    # the log file keeps lines as the program wrote them: no \r added by the terminal
    assert b"got: hello robot\n" in reader.running.log.path.read_bytes()
    assert b"\r" not in reader.running.log.path.read_bytes()


async def test_ctrl_c_typed_is_sigint_to_a_line_reader(tmp_path: Path, terminals) -> None:
    # the terminal is not its controlling terminal (the fast start): the writer sends the
    # SIGINT a terminal would, and never the byte itself
    reader = await start(tmp_path, program("line_reader.py"))
    terminals.append(reader)
    await reader.wait_for("ready")
    reader.running.write_input(b"half a line\x03")
    await reader.wait_for("interrupted by SIGINT")
    assert await reader.exit_code() == 130
    assert reader.running.typed_signals == {signal.SIGINT}
    assert "got:" not in reader.text()  # the partial line was flushed, as a terminal does


async def test_ctrl_c_on_a_controlling_terminal_is_the_kernel_s_sigint(tmp_path: Path,
                                                                      terminals) -> None:
    # under a tool (gdb) the terminal controls the child: the byte goes in, the kernel
    # signals its foreground group
    reader = await start(tmp_path, program("line_reader.py"), controlling_terminal=True)
    terminals.append(reader)
    await reader.wait_for("ready")
    reader.running.write_input(b"\x03")
    await reader.wait_for("interrupted by SIGINT")
    assert await reader.exit_code() == 130
    assert reader.running.typed_signals == set()  # not ours to send


async def test_raw_key_reader_gets_single_keys_and_ctrl_c_as_a_key(tmp_path: Path,
                                                                   terminals) -> None:
    keys = await start(tmp_path, program("raw_key_reader.py"))
    terminals.append(keys)
    await keys.wait_for("ready")
    keys.running.write_input(b"i")  # no Enter: raw mode hands over each key at once
    await keys.wait_for("key: 'i'")
    keys.running.write_input(b"\x03")
    await keys.wait_for("key: '\\x03'")
    keys.running.write_input(b"q")
    assert await keys.exit_code() == 0
    assert "bye" in keys.text()


async def test_without_a_terminal_stdin_a_keyboard_node_refuses_and_input_is_refused(
        tmp_path: Path, terminals) -> None:
    reader = await start(tmp_path, program("line_reader.py"), terminal_stdin=False)
    terminals.append(reader)
    assert await reader.exit_code() == 3
    assert "stdin is not a terminal" in reader.text()
    with pytest.raises(InputRefused, match="no terminal"):
        reader.running.write_input(b"x\r")


async def test_pipes_give_no_terminal_to_type_into(tmp_path: Path, terminals) -> None:
    reader = await start(tmp_path, program("line_reader.py"), tty=False)
    terminals.append(reader)
    assert await reader.exit_code() == 3
    with pytest.raises(InputRefused):
        reader.running.write_input(b"x")


async def test_a_node_that_never_reads_stdin_does_not_block_and_excess_is_dropped(
        tmp_path: Path, terminals) -> None:
    sleeper = await start(tmp_path, ["sh", "-c", "echo ready; exec sleep 600"])
    terminals.append(sleeper)
    await sleeper.wait_for("ready")
    dropped = 0
    for _ in range(40):  # 40 x 16 KiB: far beyond the terminal's queue and ours
        dropped += sleeper.running.write_input(b"y" * (16 * 1024))
    assert dropped > 0
    terminal = sleeper.running.terminal
    assert terminal is not None
    assert len(terminal.pending) <= LIMIT
    assert terminal.dropped == dropped
    sleeper.kill()
    with pytest.raises(InputRefused, match="closed"):
        sleeper.running.write_input(b"x")


async def test_the_child_has_its_terminal_as_controlling_terminal(tmp_path: Path,
                                                                  terminals) -> None:
    # and no signal left blocked by the way it was started (its mask is inherited by exec)
    probe = ("import os, signal; "
             "print('isatty', os.isatty(0), 'same', os.ttyname(0) == os.ttyname(1), "
             "'ctty', os.tcgetpgrp(0) == os.getpgrp() == os.getsid(0), "
             "'blocked', len(signal.pthread_sigmask(signal.SIG_BLOCK, [])), flush=True)")
    child = await start(tmp_path, ["python3", "-c", probe], controlling_terminal=True)
    terminals.append(child)
    await child.wait_for("isatty")
    assert "isatty True same True ctty True blocked 0" in child.text()
    assert await child.exit_code() == 0


async def test_by_default_the_terminal_is_stdin_without_controlling_the_child(
        tmp_path: Path, terminals) -> None:
    probe = ("import os, sys; print('isatty', os.isatty(0), flush=True); "
             "print('got', sys.stdin.readline().strip(), flush=True)")
    child = await start(tmp_path, ["python3", "-c", probe])
    terminals.append(child)
    await child.wait_for("isatty True")
    child.running.write_input(b"hello\r")
    await child.wait_for("got hello")
    assert await child.exit_code() == 0


async def test_what_waits_for_a_slow_reader_reaches_it_when_it_reads(tmp_path: Path,
                                                                     terminals) -> None:
    go = tmp_path / "go"
    slow = ("import os, sys, time, tty; tty.setraw(0); print('ready', flush=True)\n"
            f"while not os.path.exists({str(go)!r}): time.sleep(0.02)\n"
            "total = 0\n"
            "while True:\n"
            "    chunk = os.read(0, 65536)\n"
            "    total += chunk.count(b'y')\n"
            "    if chunk.endswith(b'!'): break\n"
            "print('read', total, flush=True)\n")
    reader = await start(tmp_path, ["python3", "-c", slow])
    terminals.append(reader)
    await reader.wait_for("ready")
    sent = 256 * 1024
    dropped = reader.running.write_input(b"y" * sent)  # the loop goes on meanwhile
    assert dropped > 0
    terminal = reader.running.terminal
    assert terminal is not None and terminal.pending  # waiting, not blocking
    go.touch()
    deadline = time.monotonic() + 20
    while terminal.pending:  # written as the reader takes it
        assert time.monotonic() < deadline, f"{len(terminal.pending)} bytes never written"
        await asyncio.sleep(0.02)
    reader.running.write_input(b"!")
    await reader.wait_for(f"read {sent - dropped}")
