"""A running process's record and the readers of its output channels.

Each channel (a pipe or a pseudo-terminal) is read on the event loop without a thread: one
chunk per wake-up, whole lines to the log file as bytes first, then handed to the
supervisor as screen lines.
"""

from __future__ import annotations

import asyncio
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ...plan.model import ProcessPlan
from .logfiles import LogFile
from .output import LineSplitter, screen_lines
from .spawn import Channel
from .terminal_input import InputRefused, TerminalInput

Deliver = Callable[["Running", str, list[str]], None]
"""What a reader calls with each block of lines: (process, channel name, lines)."""


class ChannelReader:
    """One output channel of a child, read on the loop until its end."""

    def __init__(self, running: Running, channel: Channel, deliver: Deliver) -> None:
        self.deliver = deliver
        self.running = running
        self.channel = channel
        self.splitter = LineSplitter()
        self.done: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self.stamp = b" " + channel.name.encode() + b" "
        self.input = TerminalInput(
            channel.fd, asyncio.get_running_loop(),
            None if channel.controlling else running.process.pid) if channel.stdin else None
        """Where typed keys go, when the child reads this terminal as its stdin."""
        asyncio.get_running_loop().add_reader(channel.fd, self._readable)

    def _readable(self) -> None:
        # one chunk per wake-up: a flooding process shares the loop with the others and
        # the UI; its pipe holds it back meanwhile, and nothing is lost
        try:
            chunk = os.read(self.channel.fd, 1 << 16)
        except BlockingIOError:
            return
        except OSError:
            chunk = b""  # EIO: a pseudo-terminal whose other side is closed
        if chunk:
            self._deliver(self.splitter.feed_block(chunk))
        else:
            self.close()

    def _deliver(self, block: bytes) -> None:
        """Whole lines, as one block: to the log file as bytes, then to the supervisor."""
        if not block:
            return
        running = self.running
        prefix = f"{time.time():.6f}".encode() + self.stamp
        running.log.write(prefix + block[:-1].replace(b"\n", b"\n" + prefix) + b"\n",
                          block.count(b"\n"))
        self.deliver(running, self.channel.name, screen_lines(block))

    def close(self) -> None:
        if self.done.done():
            return
        try:
            asyncio.get_running_loop().remove_reader(self.channel.fd)
        except RuntimeError:
            pass  # the loop is gone: nothing to unregister
        if self.input is not None:
            self.input.close()
        os.close(self.channel.fd)
        try:
            self._deliver(self.splitter.flush_block())
        finally:
            self.done.set_result(None)
            self.running.reader_closed()


@dataclass
class Running:
    """A started process: its plan, its Popen, its log file and output readers."""

    plan: ProcessPlan
    process: Any  # subprocess.Popen[bytes]: pid and returncode as asyncio's Process had
    log: LogFile
    started: float
    exited: asyncio.Future[int]
    stopping: bool = False
    readers: list[ChannelReader] = field(default_factory=list)
    pidfd: int | None = None
    reaped: bool = False

    @property
    def terminal(self) -> TerminalInput | None:
        """The child's keyboard: its terminal's writing side, while it is open."""
        for reader in self.readers:
            if reader.input is not None and not reader.input.closed:
                return reader.input
        return None

    @property
    def typed_signals(self) -> set[int]:
        """Signals the operator sent by typing ctrl+c, ctrl+\\ or ctrl+z into it."""
        return {int(sig) for reader in self.readers if reader.input is not None
                for sig in reader.input.signalled}

    def write_input(self, data: bytes) -> int:
        """Types `data` into the child's terminal (keys as a terminal sends them: `\r` for
        Enter, `\x03` for ctrl+c); returns how many bytes were dropped because the child
        does not read them. Never blocks; call it on the supervisor's loop. InputRefused
        when it has no open terminal."""
        terminal = self.terminal
        if terminal is None:
            if any(reader.input is not None for reader in self.readers):
                raise InputRefused("its terminal is closed")
            raise InputRefused("it has no terminal (its output is not shown on screen, "
                               "or emulate_tty is False)")
        return terminal.write(data)

    def reader_closed(self) -> None:
        if self.reaped and all(r.done.done() for r in self.readers):
            self.log.close()
