"""Shared by the inspector tests: real rclpy nodes in subprocesses, a bridge per scenario."""

from __future__ import annotations

import asyncio
import subprocess
import sys
from collections.abc import Awaitable, Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from tuilaunch.engine.ros.bridge import RosBridge

NODE_SCRIPT = Path(__file__).resolve().parent / "nodes" / "inspector_node.py"


@contextmanager
def ros_nodes(*argument_lists: list[str]) -> Iterator[list[subprocess.Popen[str]]]:
    """Starts one inspector_node.py per argument list, waits until each node exists, and
    kills them all afterwards, whatever happens."""
    procs: list[subprocess.Popen[str]] = []
    try:
        for arguments in argument_lists:
            procs.append(subprocess.Popen([sys.executable, str(NODE_SCRIPT), *arguments],
                                          stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                          text=True))
        for proc in procs:
            assert proc.stdout is not None
            assert proc.stdout.readline().strip() == "ready"
        yield procs
    finally:
        for proc in procs:
            proc.kill()
        for proc in procs:
            proc.wait(timeout=30)
            for stream in (proc.stdout, proc.stderr):
                if stream is not None:
                    stream.close()


def run(scenario: Callable[[RosBridge], Awaitable[Any]]) -> Any:
    """Runs one scenario with a fresh bridge, closed afterwards whatever happens."""
    async def main() -> Any:
        bridge = RosBridge("tuilaunch_inspector_test")
        try:
            return await scenario(bridge)
        finally:
            bridge.close()
    return asyncio.run(main())


async def eventually(check: Callable[[], Awaitable[Any]], timeout: float = 30.0,
                     what: str = "condition") -> Any:
    """Polls `check()` until it returns something truthy; fails after `timeout` seconds
    (generous: discovery takes seconds on a busy machine)."""
    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout
    last = None
    while loop.time() < deadline:
        last = await check()
        if last:
            return last
        await asyncio.sleep(0.1)
    raise AssertionError(f"{what} not reached within {timeout} s (last: {last!r})")
