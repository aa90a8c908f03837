"""Asks as gdb does: a prompt with no newline after it, `(gdb) `, then reads a line and
answers; `quit` ends it. A ctrl+c typed into it ends it by SIGINT (the default handler)."""

import signal
import sys

signal.signal(signal.SIGINT, signal.SIG_DFL)
print("ready", flush=True)
while True:
    sys.stdout.write("(gdb) ")
    sys.stdout.flush()
    line = sys.stdin.readline()
    if not line or line.strip() == "quit":
        break
    print(f"answer: {line.strip()}", flush=True)
print("bye", flush=True)
