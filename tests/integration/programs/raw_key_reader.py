"""Reads single keys as teleop_twist_keyboard does (tty.setraw on stdin, one byte at a time),
prints "key: <repr>" for each; 'q' quits."""

import os
import sys
import termios
import tty

fd = sys.stdin.fileno()
saved = termios.tcgetattr(fd)
tty.setraw(fd)
try:
    print("ready", flush=True)
    while True:
        key = os.read(fd, 1).decode("latin-1")
        print(f"key: {key!r}", flush=True)
        if key in ("q", ""):
            break
finally:
    termios.tcsetattr(fd, termios.TCSADRAIN, saved)
print("bye", flush=True)
