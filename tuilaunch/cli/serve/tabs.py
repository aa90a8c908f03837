"""A browser tab's TUI process, for `tuilaunch serve` (serve_web.py), started as early as
it can be: the tree on screen sooner after the URL is opened.

Where the time went (bench/serve_bench.py, a loaded 2-core machine): the page, its script
and font, and its websocket open about 0.5 s after the URL; a tab's process then took a
Python start and the TUI's imports (1.3 s and more) before Textual composed its screen
and asked the session for its tree (about 1 s). So:
- one process is kept started ahead of any tab, its imports done (Warm, serve_tab.py);
- a page's TUI starts when the page itself is asked for (Early), not when its websocket
  comes half a second later: what it draws meanwhile is held, and handed to the page's
  websocket, which names it by a ticket in its address. One no websocket claims within
  EARLY_WAIT seconds leaves (the session runs on), and at most EARLY_MAX wait at once.
"""

from __future__ import annotations

import asyncio
import json
import os
import secrets
import shlex
import signal
import sys
from asyncio.subprocess import Process
from collections.abc import Awaitable, Callable
from typing import Any, cast

from textual_serve.app_service import AppService

EARLY_WAIT = 15.0
"""Seconds a TUI started with its page waits for the page's websocket."""
WARM_AGAIN = 4.0
"""Seconds after a tab took the warm process before the next one starts."""
EARLY_MAX = 4
FRAME = 1000
"""Bytes of a TUI's output packet that can only be a drawn screen (its start's escape
sequences are a few bytes each)."""
"""Pages whose TUI is started ahead at once; more (a burst of requests) start theirs with
their websocket, as textual-serve does."""


class TabService(AppService):
    """One browser tab's TUI process (textual-serve's AppService). When the TUI leaves (`q`,
    or it could not start), the page is told by closing its websocket: it then says the
    session runs on, and offers to open it again."""

    def __init__(self, words: list[str], warm: Warm | None = None,
                 **kwargs: Any) -> None:
        # serve_tab.py, as the warm one is (start_tab_process): its words on its first line
        super().__init__(shlex.join([sys.executable, "-P", "-m", "tuilaunch.cli.serve_tab"]),
                         **kwargs)
        self.words = words
        self.warm = warm

    async def run(self) -> None:
        try:
            await super().run()
        finally:
            await self.remote_close()

    # A size told before the TUI has drawn its first screen is lost (Textual applies its
    # start size after it): the latest is kept, and told once the first screen is out.
    drawn = False
    size: tuple[int, int] | None = None

    async def set_terminal_size(self, width: int, height: int) -> None:
        self.size = (width, height)
        if self.drawn:
            await super().set_terminal_size(width, height)

    async def on_data(self, payload: bytes) -> None:
        await super().on_data(payload)
        if not self.drawn and len(payload) > FRAME:
            self.drawn = True
            if self.size is not None:
                await super().set_terminal_size(*self.size)

    async def _open_app_process(self, width: int = 80, height: int = 24) -> Process:
        """The warm process when one waits (its imports done), else a new one as
        textual-serve starts it; told its words and size."""
        process = await self.warm.take() if self.warm is not None else None
        if process is None or process.stdin is None:
            # not through a shell (textual-serve's way): the pid killed is the TUI's
            process = await start_tab_process(self._build_environment(width, height))
        assert process.stdin is not None
        process.stdin.write(json.dumps([self.words, width, height]).encode() + b"\n")
        self._process, self._stdin = process, process.stdin
        return process

    @property
    def pid(self) -> int | None:
        # textual-serve keeps the process to itself; serve kills a stuck one at its end
        process = getattr(self, "_process", None)
        return None if process is None or process.returncode is not None else process.pid

    def kill(self) -> None:
        if (pid := self.pid) is not None:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass


def tab_words(sessions: list[str], read_only: bool) -> list[str]:
    """The command a tab runs (after `tuilaunch`): attach (of several sessions, or of
    `HOST:`, the fleet view), under the web driver."""
    return ["attach", *sessions, *(["--read-only"] if read_only else [])]


class Warm:
    """One tab's process started ahead of its tab (serve_tab.py): Python and the TUI's
    imports done while nobody waits. A tab takes it, and the next is started at once."""

    def __init__(self) -> None:
        self.process: Process | None = None
        self.stopped = False

    async def start(self) -> None:
        if self.stopped or (self.process is not None and self.process.returncode is None):
            return
        # textual-serve's environment (the web driver, its colours and frame rate)
        self.process = await start_tab_process(
            AppService._build_environment(cast(AppService, _NoDebug())))

    async def take(self) -> Process | None:
        """The waiting process (None: none alive); another is started in its place once
        this one has drawn its tree (its imports would slow this one's start: 2 cores)."""
        process, self.process = self.process, None
        loop = asyncio.get_running_loop()
        loop.call_later(WARM_AGAIN, lambda: loop.create_task(self.start()))
        return process if process is not None and process.returncode is None else None

    def stop(self) -> None:
        self.stopped = True
        if self.process is not None and self.process.returncode is None:
            self.process.kill()


async def start_tab_process(environment: dict[str, str]) -> Process:
    """serve_tab.py, waiting for its tab's words on its first line."""
    return await asyncio.create_subprocess_exec(
        sys.executable, "-P", "-m", "tuilaunch.cli.serve_tab", stdin=asyncio.subprocess.PIPE,
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE, env=environment)


class _NoDebug:
    debug = False


class Held:
    """What a TUI started with its page writes before the page's websocket comes."""

    def __init__(self) -> None:
        self.items: list[bytes | str] = []
        self.closed = False

    async def write_bytes(self, data: bytes) -> None:
        self.items.append(data)

    async def write_str(self, text: str) -> None:
        self.items.append(text)

    async def close(self) -> None:
        self.closed = True


class Early:
    """TUIs started with their page, by ticket, until their websocket claims them."""

    def __init__(self, make: Callable[..., TabService]) -> None:
        self.make = make
        self.waiting: dict[str, tuple[TabService, Held]] = {}

    async def start(self, words: list[str]) -> str:
        """A ticket for the page's websocket ('' when EARLY_MAX already wait)."""
        if len(self.waiting) >= EARLY_MAX:
            return ""
        held = Held()
        tab = self.make(words, write_bytes=held.write_bytes, write_str=held.write_str,
                        close=held.close)
        await tab.start(80, 24)  # the page's size comes with its websocket
        ticket = secrets.token_urlsafe(12)
        self.waiting[ticket] = (tab, held)
        asyncio.get_running_loop().call_later(EARLY_WAIT, self._expire, ticket)
        return ticket

    def _expire(self, ticket: str) -> None:
        if (waiting := self.waiting.pop(ticket, None)) is not None:
            waiting[0].kill()  # no page came for it: it leaves, the session runs on

    async def claim(self, ticket: str, words: list[str],
                    write_bytes: Callable[[bytes], Awaitable[None]],
                    write_str: Callable[[str], Awaitable[None]],
                    close: Callable[[], Awaitable[None]]) -> TabService | None:
        """The TUI started for this page, now writing to its websocket (what it drew so
        far first, in order); None: no such ticket, or one for other sessions."""
        waiting = self.waiting.pop(ticket, None) if ticket else None
        if waiting is None:
            return None
        tab, held = waiting
        if tab.words != words:
            self.waiting[ticket] = waiting
            return None
        while held.items:  # no await between the last check and the switch: no reorder
            item = held.items.pop(0)
            await (write_bytes(item) if isinstance(item, bytes) else write_str(item))
        tab.remote_write_bytes, tab.remote_write_str, tab.remote_close = \
            write_bytes, write_str, close
        if held.closed:
            await close()
        return tab

    def stop(self) -> None:
        for tab, _held in self.waiting.values():
            tab.kill()
        self.waiting.clear()


__all__ = ["EARLY_MAX", "EARLY_WAIT", "Early", "TabService", "Warm", "tab_words"]
