"""Turning a process's raw bytes into lines: partial lines, `\\r` progress, bad UTF-8, tabs.

Log files keep each line's bytes as the process wrote them (`feed_raw`), but for a line
rewritten with `\r` (a progress bar), of which they keep the last state; what a screen
shows is cleaned once (`screen_text`, and `expand_tabs` once its colour codes are
gone: vocabulary/text.py, which the clients share).
"""

from __future__ import annotations

import re

from ..vocabulary.text import screen_text

MAX_LINE = 8 << 20
"""The longest line kept whole: 8 MiB, eight times a 1 MiB robot description. Longer ones
are cut into pieces of this size, so a process that never writes a newline costs at most
this much per channel, and a piece sent to a client (JSON escapes a byte into at most six)
stays below the session protocol's MAX_MESSAGE."""


def screen_lines(block: bytes) -> list[str]:
    """The screen text of a block of whole lines (each ending in `\n`)."""
    body = block[:-1]
    text = body.decode("utf-8", errors="replace")
    if "\r" in text or "\x00" in text or "\b" in text:
        return [screen_text(line) for line in body.split(b"\n")]
    return text.split("\n")


REWOUND = re.compile(rb"[^\r\n]*\r(?=[^\r\n])")
"""What a `\r` followed by more text rewinds over: gone from the line a terminal shows."""


def last_states(block: bytes) -> bytes:
    """Whole lines with what `\r` rewrote taken out (`10%\r20%\r100%` is `100%`); a
    terminal's `\r\n` endings stay as they are. Counted first: most blocks have none."""
    if b"\r" not in block or block.count(b"\r") == block.count(b"\r\n"):
        return block
    return REWOUND.sub(b"", block)


def rewritten(tail: bytes) -> bytes:
    """An unfinished line as a terminal leaves it: what a `\r` followed by more rewrote is
    gone. A `\r` at the very end stays (its `\n` may come in the next chunk: a terminal's
    lines end in `\r\n`)."""
    rewind = tail.rfind(b"\r", 0, len(tail) - 1)
    return tail[rewind + 1:] if rewind >= 0 else tail


class LineSplitter:
    """Feeds chunks, yields whole lines; keeps the unfinished tail for the next chunk.

    A line is kept whole up to MAX_LINE bytes (a robot description, a JSON dump of a
    message on one line); past that it is cut into MAX_LINE pieces, so a process that
    never writes a newline holds at most that much. The tail is kept as the chunks it came
    in and joined once, when its line ends: a long line costs its length, not its length
    times its chunks.
    """

    def __init__(self) -> None:
        self._pieces: list[bytes] = []
        self._size = 0

    @property
    def tail(self) -> bytes:
        """The unfinished line so far (a prompt waiting for its answer)."""
        return b"".join(self._pieces)

    @property
    def tail_size(self) -> int:
        """How long the unfinished line is, without joining it."""
        return self._size

    def tail_head(self, limit: int) -> bytes:
        """The first `limit` bytes of the unfinished line (what a screen shows of a
        partial line), without joining the rest."""
        head: list[bytes] = []
        size = 0
        for piece in self._pieces:
            if size >= limit:
                break
            head.append(piece[:limit - size])
            size += len(head[-1])
        return b"".join(head)

    def _keep(self, tail: bytes) -> None:
        self._pieces = [tail] if tail else []
        self._size = len(tail)

    def feed_block(self, chunk: bytes) -> bytes:
        """The complete lines this chunk ends, as one block of bytes, each line ending in
        `\n` (empty when none): a flood is handled a chunk at a time, not a line at a time.

        A line rewritten with `\r` (a progress bar, a download) is kept as a terminal shows
        it: its last state only, so it is never cut at MAX_LINE mid-word however long it
        keeps rewriting, and the log file gets that last state once the line ends."""
        if not chunk:
            return b""
        end = chunk.rfind(b"\n") + 1
        if end:
            # the old tail's rewrites are already taken out, but for a `\r` at its very end
            data = chunk if not self._pieces else b"".join(self._pieces) + chunk
            cut = len(data) - len(chunk) + end
            block = last_states(data[:cut])
            if self._size + chunk.find(b"\n") > MAX_LINE:
                first = block.find(b"\n")  # the line the tail was: cut as it would have been
                block = _cut(block[:first]) + block[first:]
            self._keep(rewritten(chunk[end:]))
        else:
            block = b""
            if self._pieces and self._pieces[-1].endswith(b"\r"):
                self._keep(b"")  # `\r` then more: the line starts again
            rest = rewritten(chunk)
            if len(rest) < len(chunk):
                self._keep(b"")  # rewound within this chunk: what came before is gone
            self._pieces.append(rest)
            self._size += len(rest)
        if self._size > MAX_LINE:
            tail = _cut(b"".join(self._pieces))
            whole = tail.rfind(b"\n") + 1
            block += tail[:whole]
            self._keep(tail[whole:])
        return block

    def flush_block(self) -> bytes:
        tail = b"".join(self._pieces)
        self._keep(b"")
        return tail + b"\n" if tail else b""

    def feed(self, chunk: bytes) -> list[str]:
        """Screen lines: a progress bar drawn with `\\r` becomes one line, not thousands."""
        block = self.feed_block(chunk)
        return screen_lines(block) if block else []

    def flush(self) -> list[str]:
        block = self.flush_block()
        return screen_lines(block) if block else []


def _cut(line: bytes) -> bytes:
    """A line longer than MAX_LINE as its pieces of MAX_LINE, each but the last ending in
    `\n`."""
    return b"\n".join(line[start:start + MAX_LINE] for start in range(0, len(line), MAX_LINE))
