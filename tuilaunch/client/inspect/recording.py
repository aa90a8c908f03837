"""A recording pulled from a session into an MCAP file on this computer: `tuilaunch record`
(a blocking link) and the Topics tab's recording key (the TUI's LaunchPort) both feed a
`RecordFile` with the session's `record_take` replies (engine/ros/record/recorder.py).

Pulled, not pushed: the session keeps what the client has not taken yet, bounded, and the
client asks again as soon as it has written the last batch, so a slow link (ssh) costs the
oldest messages, counted and said, never the session's memory or its other clients.
"""

from __future__ import annotations

import base64
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

from ...engine.ros.record.mcap_out import McapOut, open_exact, open_new
from ...engine.ros.record.tape import Channel
from ...engine.run.vocabulary.requests import RecordStart, RecordStop, RecordTake


def default_stem(name: str) -> str:
    """`NAME-YYYYmmdd-HHMMSS`: the session's name without its host."""
    return f"{name.rsplit(':', 1)[-1] or 'session'}-{time.strftime('%Y%m%d-%H%M%S')}"


class RecordFile:
    """The MCAP file a recording is written to, and what it holds so far."""

    def __init__(self, output: str | None, name: str) -> None:
        if output is None:
            path, stream = open_new(Path.cwd(), default_stem(name))
        else:
            path = Path(output)
            stream = open_exact(path)
        self.path = path
        self.out = McapOut(stream, path)
        self.dropped = 0
        self.topics: set[str] = set()
        self.waiting: dict[str, str] = {}
        self.started = time.monotonic()
        self.closed = False

    def apply(self, reply: dict[str, Any]) -> int:
        """One `record_take` reply written; the number of messages it held."""
        for channel in reply.get("channels") or []:
            self.out.channel(Channel(**channel))
            self.topics.add(channel["topic"])
        messages = reply.get("messages") or []
        self.out.add([(topic, int(time_ns), base64.b64decode(data))
                      for topic, time_ns, data in messages])
        self.dropped += int(reply.get("dropped") or 0)
        self.waiting = dict(reply.get("waiting") or {})
        return len(messages)

    @property
    def size(self) -> int:
        return self.out.size()

    def close(self) -> None:
        if not self.closed:
            self.closed = True
            self.out.close()

    def summary(self) -> str:
        seconds = time.monotonic() - self.started
        text = (f"{self.path}: {self.out.messages} messages on {len(self.topics)} channels, "
                f"{self.size / 1e6:.1f} MB, {seconds:.1f} s")
        if self.dropped:
            text += (f"; {self.dropped} messages were dropped: the link carried less than "
                     "the topics sent")
        for topic, why in sorted(self.waiting.items()):
            text += f"\n  {topic} not recorded: {why}"
        return text


Request = Callable[..., Awaitable[Any]]


class LiveRecording:
    """A recording run by the TUI over its session's `request`: `run` pulls until `stop`."""

    def __init__(self, request: Request, name: str, topics: list[str],
                 output: str | None = None) -> None:
        self.request = request
        self.topics = topics
        self.file = RecordFile(output, name)
        self.stopping = False
        self.error: str | None = None

    async def run(self) -> None:
        import asyncio

        try:
            answer = await self.request(RecordStart(topics=self.topics))
            ident = answer["recording"]
            while not self.stopping:
                reply = await self.request(RecordTake(recording=ident))
                await asyncio.to_thread(self.file.apply, reply)
            reply = await self.request(RecordTake(recording=ident, wait=0))
            await asyncio.to_thread(self.file.apply, reply)
            await self.request(RecordStop(recording=ident))
        except Exception as exc:  # the link or the session: the file is closed all the same
            self.error = str(exc)
        finally:
            await asyncio.to_thread(self.file.close)

    def stop(self) -> None:
        self.stopping = True


__all__ = ["LiveRecording", "RecordFile", "default_stem"]
