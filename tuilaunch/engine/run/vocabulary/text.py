"""A line's text as a screen shows it: colour codes, tabs, backspaces and `\\r` rewinds.

Shared by the engine (which cleans a process's lines once, process/output.py) and its
clients (which show lines read back from the log files), so a pane and a log agree.
"""

from __future__ import annotations

import re
import unicodedata

ANSI = re.compile(r"\x1b\[[0-9;?]*[ -/]*[@-~]|\x1b\][^\x07]*\x07")


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
