"""Starting a test program through spawn.py and the run layer's readers, as the supervisor
does, without a launch: its screen lines collected, its keyboard reachable."""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from tuilaunch.engine.run.process.logfiles import LogFile
from tuilaunch.engine.run.process.readers import ChannelReader, Running
from tuilaunch.engine.run.process.spawn import spawn

PROGRAMS = Path(__file__).parent / "programs"
DEADLINE = 20.0


class Terminal:
    """One spawned program: `lines` is what its panes would show, by channel."""

    def __init__(self, running: Running) -> None:
        self.running = running
        self.lines: list[tuple[str, str]] = []

    def deliver(self, _running: Running, channel: str, lines: list[str]) -> None:
        self.lines.extend((channel, line) for line in lines)

    def text(self, channel: str | None = None) -> str:
        return "\n".join(line for name, line in self.lines if channel in (None, name))

    async def wait_for(self, needle: str, channel: str | None = None) -> None:
        deadline = time.monotonic() + DEADLINE
        while needle not in self.text(channel):
            if time.monotonic() > deadline:
                raise AssertionError(f"{needle!r} never came; got:\n{self.text()}")
            await asyncio.sleep(0.02)

    async def exit_code(self) -> int:
        deadline = time.monotonic() + DEADLINE
        while (code := self.running.process.poll()) is None:
            if time.monotonic() > deadline:
                raise AssertionError(f"still running; output:\n{self.text()}")
            await asyncio.sleep(0.02)
        await asyncio.wait_for(asyncio.gather(*(r.done for r in self.running.readers)),
                               DEADLINE)
        return int(code)

    def kill(self) -> None:
        if self.running.process.poll() is None:
            try:
                os.killpg(self.running.process.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.running.process.wait()
        for reader in self.running.readers:
            reader.close()


async def start(tmp_path: Path, cmd: list[str], *, tty: bool = True,
                **options: Any) -> Terminal:
    child = spawn(cmd, dict(os.environ, PYTHONUNBUFFERED="1"), None, tty, **options)
    loop = asyncio.get_running_loop()
    plan: Any = SimpleNamespace(id="program")
    log = LogFile(tmp_path / f"program-{child.popen.pid}.log", lambda text: None)
    running = Running(plan, child.popen, log, time.monotonic(), loop.create_future())
    terminal = Terminal(running)
    for channel in child.channels:
        running.readers.append(ChannelReader(running, channel, terminal.deliver))
    return terminal


def program(name: str, *args: str) -> list[str]:
    return [sys.executable, str(PROGRAMS / name), *args]
