"""A keyboard node slow to stop, so restarting it takes a second (a node saving its state
on SIGINT): with a terminal it reads lines as line_reader does; without one it says so and
waits for a restart that gives it one."""

import signal
import sys
import time


def stop_slowly(*_: object) -> None:
    time.sleep(1.0)
    print("stopped slowly", flush=True)
    sys.exit(130)


signal.signal(signal.SIGINT, stop_slowly)
if not sys.stdin.isatty():
    print("no terminal: waiting", flush=True)
    while True:
        signal.pause()
print("ready", flush=True)
for line in sys.stdin:
    print("got: " + line.rstrip("\n"), flush=True)
