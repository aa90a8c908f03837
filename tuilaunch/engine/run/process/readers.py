"""A running process's record and the readers of its output channels.

Each channel (a pipe or a pseudo-terminal) is read on the event loop without a thread: one
chunk per wake-up, whole lines to the log file as bytes first, then handed to the
supervisor as screen lines. A line left unfinished while the channel is quiet (gdb's
`(gdb) `, a question waiting for its answer) is handed on as it stands, to be shown until
the whole line replaces it; the log file gets it once it is whole.
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
from .output import LineSplitter, screen_lines, screen_text
from .spawn import Channel
from .terminal_input import InputRefused, TerminalInput

DRAIN_CHUNKS = 256
"""Reads, at most, of what is already waiting in a channel when it is closed (1 MB from a
terminal, 16 MB from a pipe): a grandchild that floods for ever does not hold the end."""

Deliver = Callable[["Running", str, list[str]], None]
"""What a reader calls with each block of lines: (process, channel name, lines)."""
Partial = Callable[["Running", str, str], None]
"""What a reader calls with an unfinished line the process left waiting: (process, channel
name, the line so far as a screen shows it)."""

PROGRESS_EVERY = 0.1
"""Seconds between two showings of a line rewritten with `\r` while it keeps changing: ten
a second is what the eye reads of a progress bar; the UI repaints at most that often."""

PARTIAL_AFTER = 0.05
"""Seconds a channel must stay quiet before its unfinished line is shown: a prompt waits
that long for sure, while a flood's chunks that end mid-line are never shown half."""


PARTIAL_SHOWN = 64 * 1024
"""The most of an unfinished line handed on to be shown before it ends: a line that grows
to megabytes without a newline is not sent again and again as it grows."""


NO_TERMINAL = ("it has no terminal: it was started with pipes, as without emulate_tty=True "
               "in ros2 launch (`i` in the TUI, or `tuilaunch restart --terminal`, restarts "
               "it with one)")
"""Why a process cannot be typed into, said the same by every way in."""


class ChannelReader:
    """One output channel of a child, read on the loop until its end."""

    def __init__(self, running: Running, channel: Channel, deliver: Deliver,
                 partial: Partial | None = None) -> None:
        self.deliver = deliver
        self.partial = partial
        self._shown_tail = b""  # the unfinished line handed on last, not to repeat it
        self._read_since = False  # a chunk came since the quiet timer was set
        self._quiet: asyncio.TimerHandle | None = None
        self._progress_shown = 0.0  # when a line rewritten with \r was last handed on
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
        if not chunk:
            self.close()
            return
        self._deliver(self.splitter.feed_block(chunk))
        if self.partial is not None and self.splitter.tail_size:
            if b"\r" in chunk and time.monotonic() - self._progress_shown >= PROGRESS_EVERY:
                # a line rewritten in place (a progress bar) never goes quiet: shown as it
                # stands now and then, as a terminal would, not once it ends
                self._progress_shown = time.monotonic()
                self._show_tail()
            self._read_since = True
            if self._quiet is None:
                self._quiet = asyncio.get_running_loop().call_later(
                    PARTIAL_AFTER, self._quiet_now)

    def _quiet_now(self) -> None:
        """The quiet timer: hands on the unfinished line once nothing came for a while."""
        self._quiet = None
        if not self.splitter.tail_size or self.done.done():
            return
        if self._read_since:  # still coming: look again later (one timer per channel)
            self._read_since = False
            self._quiet = asyncio.get_running_loop().call_later(PARTIAL_AFTER, self._quiet_now)
            return
        self._show_tail()

    def _show_tail(self) -> None:
        # a screen's preview of the unfinished line: its head; the whole line comes when
        # it ends (a prompt is short; a line longer than this is no prompt)
        tail = self.splitter.tail_head(PARTIAL_SHOWN)
        if tail != self._shown_tail and self.partial is not None:
            self._shown_tail = tail
            self.partial(self.running, self.channel.name, screen_text(tail))

    def _deliver(self, block: bytes) -> None:
        """Whole lines, as one block: to the log file as bytes, then to the supervisor."""
        if not block:
            return
        self._shown_tail = b""  # the whole lines replace what was shown of the last one
        running = self.running
        running.log.write_stamped(f"{time.time():.6f}".encode() + self.stamp, block)
        self.deliver(running, self.channel.name, screen_lines(block))

    def _drain(self) -> None:
        """What the channel already holds is read and logged before it is closed: a launch
        that ends while a grandchild's output waits there (read one chunk per wake-up, and
        the loop was slow) loses none of it."""
        for _ in range(DRAIN_CHUNKS):
            try:
                chunk = os.read(self.channel.fd, 1 << 16)
            except OSError:  # BlockingIOError: nothing more now; EIO: the other side closed
                return
            if not chunk:
                return
            self._deliver(self.splitter.feed_block(chunk))

    def close(self) -> None:
        if self.done.done():
            return
        try:
            asyncio.get_running_loop().remove_reader(self.channel.fd)
        except RuntimeError:
            pass  # the loop is gone: nothing to unregister
        self._drain()
        if self.input is not None:
            self.input.close()
        if self._quiet is not None:
            self._quiet.cancel()
            self._quiet = None
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
    gone: asyncio.Event = field(default_factory=asyncio.Event)
    """Set once its end is told (state, `exited` event): a stop waits for it, so what
    starts it again (a restart, a relaunch) finds it no longer running."""

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
            raise InputRefused(NO_TERMINAL)
        return terminal.write(data)

    def reader_closed(self) -> None:
        if self.reaped and all(r.done.done() for r in self.readers):
            self.log.close()
