"""Turning a process's raw bytes into lines: partial lines, `\\r` progress, bad UTF-8."""

from __future__ import annotations

import re

ANSI = re.compile(r"\x1b\[[0-9;?]*[ -/]*[@-~]|\x1b\][^\x07]*\x07")
MAX_LINE = 64 * 1024


def strip_ansi(text: str) -> str:
    return ANSI.sub("", text)


class LineSplitter:
    """Feeds chunks, yields whole lines; keeps the unfinished tail for the next chunk.

    A bare `\\r` rewinds the line as a terminal would, so a progress bar becomes one line,
    not thousands; a line longer than MAX_LINE is cut into pieces rather than held forever.
    """

    def __init__(self) -> None:
        self._tail = b""

    def feed(self, chunk: bytes) -> list[str]:
        data = self._tail + chunk
        parts = data.split(b"\n")
        self._tail = parts.pop()
        while len(self._tail) > MAX_LINE:
            parts.append(self._tail[:MAX_LINE])
            self._tail = self._tail[MAX_LINE:]
        return [self._decode(p) for p in parts]

    def flush(self) -> list[str]:
        tail, self._tail = self._tail, b""
        return [self._decode(tail)] if tail else []

    @staticmethod
    def _decode(raw: bytes) -> str:
        if raw.endswith(b"\r"):
            raw = raw[:-1]
        if b"\r" in raw:
            raw = raw.rsplit(b"\r", 1)[1]
        return raw.decode("utf-8", errors="replace").replace("\x00", "")
