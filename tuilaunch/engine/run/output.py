"""Turning a process's raw bytes into lines: partial lines, `\\r` progress, bad UTF-8.

Log files keep each line's bytes as the process wrote them (`feed_raw`); what a screen
shows is cleaned once, here (`screen_text`).
"""

from __future__ import annotations

import re

ANSI = re.compile(r"\x1b\[[0-9;?]*[ -/]*[@-~]|\x1b\][^\x07]*\x07")
MAX_LINE = 64 * 1024


def strip_ansi(text: str) -> str:
    return ANSI.sub("", text)


def screen_text(raw: bytes) -> str:
    """What a terminal would leave on the line: a bare `\\r` rewinds it, NULs show nothing."""
    if raw.endswith(b"\r"):
        raw = raw[:-1]
    if b"\r" in raw:
        raw = raw.rsplit(b"\r", 1)[1]
    return raw.decode("utf-8", errors="replace").replace("\x00", "")


class LineSplitter:
    """Feeds chunks, yields whole lines; keeps the unfinished tail for the next chunk.

    A line longer than MAX_LINE is cut into pieces rather than held forever.
    """

    def __init__(self) -> None:
        self._tail = b""

    def feed_raw(self, chunk: bytes) -> list[bytes]:
        data = self._tail + chunk if self._tail else chunk
        parts = data.split(b"\n")
        self._tail = parts.pop()
        while len(self._tail) > MAX_LINE:
            parts.append(self._tail[:MAX_LINE])
            self._tail = self._tail[MAX_LINE:]
        return parts

    def flush_raw(self) -> list[bytes]:
        tail, self._tail = self._tail, b""
        return [tail] if tail else []

    def feed(self, chunk: bytes) -> list[str]:
        """Screen lines: a progress bar drawn with `\\r` becomes one line, not thousands."""
        return [screen_text(p) for p in self.feed_raw(chunk)]

    def flush(self) -> list[str]:
        return [screen_text(p) for p in self.flush_raw()]
