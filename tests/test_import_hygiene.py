"""The engine must run without Textual: the headless mode and tools depend on it."""

from __future__ import annotations

import subprocess
import sys


def test_engine_imports_no_textual():
    code = ("import sys, tuilaunch.engine, tuilaunch.engine.plan.resolve, "
            "tuilaunch.engine.describe.compat, tuilaunch.engine.run.supervisor;"
            "bad = sorted(m for m in sys.modules if m == 'textual' or m.startswith('textual.'));"
            "print(bad); sys.exit(1 if bad else 0)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
