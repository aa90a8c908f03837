"""Prints `before`, one line of LENGTH bytes (argv[1], default 1 MiB) written in 4 KB pieces
with a flush after each (as a logger dumping a big message does), then `after`, then
waits to be stopped. The long line is `<<` + `0123456789` repeated + `>>`."""

import sys
import time

length = int(sys.argv[1]) if len(sys.argv) > 1 else 1 << 20
body = ("0123456789" * (length // 10 + 1))[:length - 4]
line = "<<" + body + ">>\n"
sys.stdout.write("before\n")
sys.stdout.flush()
for start in range(0, len(line), 4096):
    sys.stdout.write(line[start:start + 4096])
    sys.stdout.flush()
sys.stdout.write("after\n")
sys.stdout.flush()
while True:
    time.sleep(60)
