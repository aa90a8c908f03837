"""gdb for tests that debug a crashing program: skipped, with how to get it, where missing."""

from __future__ import annotations

import shutil

import pytest

GDB = shutil.which("gdb")

requires_gdb = pytest.mark.skipif(
    GDB is None, reason="gdb is not installed (apt-get install gdb) : the test runs a "
                        "crashing program under it")


def gdb_batch(*argv: str) -> list[str]:
    """gdb running `argv` to its end (or crash) and printing the backtrace, then quitting."""
    assert GDB is not None
    return [GDB, "-q", "-batch", "-nx", "-ex", "run", "-ex", "bt", "--args", *argv]
