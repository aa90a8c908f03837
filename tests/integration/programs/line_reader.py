"""Reads lines from its terminal and prints each back; refuses a stdin that is not one, as
many keyboard nodes do; says so when ctrl+c interrupts it."""

import sys

if not sys.stdin.isatty():
    print("line_reader: stdin is not a terminal", flush=True)
    sys.exit(3)
try:
    # "ready" inside the try: a ctrl+c typed as soon as it shows may land while print()
    # is still returning (seen under two CPU burners)
    print("ready", flush=True)
    for line in sys.stdin:
        print("got: " + line.rstrip("\n"), flush=True)
except KeyboardInterrupt:
    print("interrupted by SIGINT", flush=True)
    sys.exit(130)
print("end of input", flush=True)
