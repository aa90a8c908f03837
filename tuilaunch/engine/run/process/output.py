"""Turning a process's raw bytes into lines: partial lines, `\\r` progress, bad UTF-8, tabs.

Log files keep each line's bytes as the process wrote them (`feed_raw`), but for a line
rewritten with `\r` (a progress bar), of which they keep the last state; what a screen
shows is cleaned once, here (`screen_text`, and `expand_tabs` once its colour codes are
gone).
"""

from __future__ import annotations

import re
import unicodedata

ANSI = re.compile(r"\x1b\[[0-9;?]*[ -/]*[@-~]|\x1b\][^\x07]*\x07")
MAX_LINE = 64 * 1024


def strip_ansi(text: str) -> str:
    return ANSI.sub("", text)


TAB_STOP = 8
"""A terminal's tab stops: every 8 columns."""


def cell_width(char: str) -> int:
    """Columns a character takes on a terminal: 2 for a wide one (CJK), 0 for a combining
    mark, else 1."""
    if char.isascii():
        return 1
    if unicodedata.combining(char):
        return 0
    return 2 if unicodedata.east_asian_width(char) in "WF" else 1


def expand_tabs(text: str) -> str:
    """Each tab as the spaces to the next 8-column stop, as a terminal moves the cursor:
    gdb's `120\t../sysdeps/...` and ps's tables line up, and a screen drawing the line
    never meets a tab (whose width it does not know). Columns count cells: a wide
    character takes two. Call it on a line without colour codes (they take no columns)."""
    if "\t" not in text:
        return text
    if text.isascii():
        return text.expandtabs(TAB_STOP)
    out: list[str] = []
    column = 0
    for char in text:
        if char == "\t":
            spaces = TAB_STOP - column % TAB_STOP
            out.append(" " * spaces)
            column += spaces
        else:
            out.append(char)
            column += cell_width(char)
    return "".join(out)


def backspaced(text: str) -> str:
    """What backspaces leave on a line: a terminal moves the cursor one column back and what
    comes next overwrites, so a line reader's echo of an erased character (`\\b \\b`)
    leaves nothing, not a space."""
    if "\b" not in text:
        return text
    out: list[str] = []
    cursor = 0
    for char in text:
        if char == "\b":
            cursor = max(cursor - 1, 0)
            continue
        if cursor < len(out):
            out[cursor] = char
        else:
            out.append(char)
        cursor += 1
    return "".join(out).rstrip(" ")


def screen_text(raw: bytes) -> str:
    """What a terminal would leave on the line: a bare `\\r` rewinds it, a backspace steps
    back, NULs show nothing."""
    if raw.endswith(b"\r"):
        raw = raw[:-1]
    if b"\r" in raw:
        raw = raw.rsplit(b"\r", 1)[1]
    return backspaced(raw.decode("utf-8", errors="replace").replace("\x00", ""))


def screen_str(text: str) -> str:
    """`screen_text` of a line already decoded, as the log files' lines are read back."""
    if "\r" not in text and "\x00" not in text and "\b" not in text:
        return text
    if text.endswith("\r"):
        text = text[:-1]
    return backspaced(text.rsplit("\r", 1)[-1].replace("\x00", ""))


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

    A line longer than MAX_LINE is cut into pieces rather than held forever.
    """

    def __init__(self) -> None:
        self._tail = b""

    @property
    def tail(self) -> bytes:
        """The unfinished line so far (a prompt waiting for its answer)."""
        return self._tail

    def feed_block(self, chunk: bytes) -> bytes:
        """The complete lines this chunk ends, as one block of bytes, each line ending in
        `\n` (empty when none): a flood is handled a chunk at a time, not a line at a time.

        A line rewritten with `\r` (a progress bar, a download) is kept as a terminal shows
        it: its last state only, so it is never cut at MAX_LINE mid-word however long it
        keeps rewriting, and the log file gets that last state once the line ends."""
        data = self._tail + chunk if self._tail else chunk
        end = data.rfind(b"\n") + 1
        block, tail = last_states(data[:end]), rewritten(data[end:])
        if len(tail) > MAX_LINE:
            pieces = []
            while len(tail) > MAX_LINE:
                pieces.append(tail[:MAX_LINE])
                tail = tail[MAX_LINE:]
            block += b"\n".join(pieces) + b"\n"
        self._tail = tail
        return block

    def flush_block(self) -> bytes:
        tail, self._tail = self._tail, b""
        return tail + b"\n" if tail else b""

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
