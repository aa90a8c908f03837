"""The engine must run without Textual: the headless mode and tools depend on it."""

from __future__ import annotations

import subprocess
import sys


def test_engine_imports_no_textual():
    code = ("import sys, tuilaunch.engine, tuilaunch.engine.plan.resolve, "
            "tuilaunch.engine.describe.python.compat, tuilaunch.engine.run.supervisor.supervisor;"
            "bad = sorted(m for m in sys.modules if m == 'textual' or m.startswith('textual.'));"
            "print(bad); sys.exit(1 if bad else 0)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr


def test_client_and_session_commands_import_no_textual():
    """The session client and the headless and session commands start without Textual: it
    is loaded only when a TUI opens."""
    code = ("import sys, tuilaunch.client.link, tuilaunch.client.remote_supervisor, "
            "tuilaunch.cli, tuilaunch.cli.commands, tuilaunch.cli.headless;"
            "bad = sorted(m for m in sys.modules if m == 'textual' or m.startswith('textual.'));"
            "print(bad); sys.exit(1 if bad else 0)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
