"""Textual's key events as the bytes a terminal sends for them (xterm's), for typing into a
node's terminal; and the partial line the operator has typed so far, to show it before the
node's echo arrives (a line reader's echo comes as one line, at Enter)."""

from __future__ import annotations

RELEASE_KEYS = frozenset({"ctrl+right_square_bracket", "ctrl+]"})
"""ctrl+] gives the keys back to tuilaunch (telnet's escape): no program needs it."""

SEQUENCES = {
    "enter": "\r", "tab": "\t", "backspace": "\x7f", "ctrl+h": "\x08", "escape": "\x1b",
    "up": "\x1b[A", "down": "\x1b[B", "right": "\x1b[C", "left": "\x1b[D",
    "home": "\x1b[H", "end": "\x1b[F", "insert": "\x1b[2~", "delete": "\x1b[3~",
    "pageup": "\x1b[5~", "pagedown": "\x1b[6~", "shift+tab": "\x1b[Z",
    "f1": "\x1bOP", "f2": "\x1bOQ", "f3": "\x1bOR", "f4": "\x1bOS", "f5": "\x1b[15~",
    "f6": "\x1b[17~", "f7": "\x1b[18~", "f8": "\x1b[19~", "f9": "\x1b[20~",
    "f10": "\x1b[21~", "f11": "\x1b[23~", "f12": "\x1b[24~", "space": " ",
}
"""Keys whose bytes Textual does not give as the event's character."""


def key_bytes(key: str, character: str | None) -> str | None:
    """What the terminal sends for a key: `\\r` for Enter, `\\x03` for ctrl+c, `\\x1b[A` for
    up; None for a key with no bytes (a lone modifier)."""
    if key in SEQUENCES:
        return SEQUENCES[key]
    if character:
        return character
    if key.startswith("ctrl+") and len(key) == 6 and key[5].isalpha():
        return chr(ord(key[5].lower()) - ord("a") + 1)
    return None


def is_release(key: str, character: str | None) -> bool:
    return key in RELEASE_KEYS or character == "\x1d"


def edit_line(line: str, typed: str) -> str:
    """The partial line after `typed`, as a canonical terminal edits it: Enter, ctrl+c and
    ctrl+u start afresh, backspace removes a character, escape sequences add nothing."""
    for char in typed:
        if char in "\r\n\x03\x15\x04":
            line = ""
        elif char in "\x7f\x08":
            line = line[:-1]
        elif char == "\x1b":
            return line  # a cursor key: the line's content is the program's to tell
        elif char.isprintable():
            line += char
    return line
