"""gdb for tests that debug a crashing program: skipped, with how to get it, where missing."""

from __future__ import annotations

import shutil

import pytest

from .system_packages import apt_install

GDB = shutil.which("gdb") or (apt_install("gdb") and shutil.which("gdb")) or None

requires_gdb = pytest.mark.skipif(
    GDB is None, reason="gdb is not installed and could not be (apt-get install gdb): "
                        "the test runs a crashing program under it")


def gdb_batch(*argv: str) -> list[str]:
    """gdb running `argv` to its end (or crash) and printing the backtrace, then quitting."""
    assert GDB is not None
    return [GDB, "-q", "-batch", "-nx", "-ex", "run", "-ex", "bt", "--args", *argv]
