"""The supervisor's own event loop, in its own thread, for an interactive UI.

Reading and logging a flood of output then never competes with drawing the screen, and
drawing never delays supervision (kill timers, respawns). The UI talks to it only by
submitting coroutines and draining the thread-safe EventBuffer.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
from collections.abc import Coroutine
from typing import Any, TypeVar

T = TypeVar("T")


class EngineThread:
    def __init__(self) -> None:
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._main, name="tuilaunch-engine", daemon=True)
        self._thread.start()

    def _main(self) -> None:
        asyncio.set_event_loop(self.loop)
        self.loop.run_forever()

    def submit(self, coroutine: Coroutine[Any, Any, T]) -> concurrent.futures.Future[T]:
        return asyncio.run_coroutine_threadsafe(coroutine, self.loop)

    async def run(self, coroutine: Coroutine[Any, Any, T]) -> T:
        """Runs on the engine loop; awaitable from any other loop."""
        return await asyncio.wrap_future(self.submit(coroutine))

    def call(self, function: Any, *args: Any) -> Any:
        """A plain function on the engine thread, waited for (for setup, not hot paths)."""

        async def wrapper() -> Any:
            return function(*args)

        return self.submit(wrapper()).result(timeout=30)

    def stop(self) -> None:
        """Cancels what still runs there (waiting triggers, readers), then ends the loop."""
        if self.loop.is_running():
            try:
                self.submit(self._cancel_all()).result(timeout=10)
            except (concurrent.futures.TimeoutError, RuntimeError):
                pass
            self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(timeout=10)

    async def _cancel_all(self) -> None:
        current = asyncio.current_task()
        tasks = [t for t in asyncio.all_tasks() if t is not current]
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
