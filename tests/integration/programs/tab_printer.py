"""Prints what gdb and ps print: lines with tabs (a source line number, a table), then
waits to be stopped."""

import sys
import time

print("120\t../sysdeps/unix/sysv/linux/nanosleep.c: No such file or directory.")
print("PID\tTTY\tTIME\tCMD")
print("1\tpts/0\t00:00:01\tbash")
print("12345678\tpts/12\t00:00:00\tps")
print("ab\tcd\tend", flush=True)
sys.stdout.flush()
time.sleep(3600)
