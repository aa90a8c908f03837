"""Floods: `line N` (numbered from 1), about RATE lines a second (argv[1], default 2000),
in small bursts, until stopped."""

import sys
import time

rate = int(sys.argv[1]) if len(sys.argv) > 1 else 2000
burst = max(rate // 100, 1)
number = 0
start = time.monotonic()
while True:
    sys.stdout.write("".join(f"line {number + i + 1} of a flood\n" for i in range(burst)))
    sys.stdout.flush()
    number += burst
    lag = start + number / rate - time.monotonic()
    if lag > 0:
        time.sleep(lag)
