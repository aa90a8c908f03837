"""The engine must run without Textual: the headless mode and tools depend on it."""

from __future__ import annotations

import pytest

from ..conftest import python_prints


@pytest.mark.parametrize("modules", [
    # the engine itself
    "tuilaunch.engine, tuilaunch.engine.plan.resolve, "
    "tuilaunch.engine.describe.python.compat, tuilaunch.engine.run.supervisor.supervisor",
    # the session client and the headless and session commands: Textual is loaded only when
    # a TUI opens
    "tuilaunch.client.link, tuilaunch.client.remote_supervisor, "
    "tuilaunch.cli, tuilaunch.cli.commands, tuilaunch.cli.headless",
], ids=["engine", "client-and-session-commands"])
def test_imports_no_textual(modules):
    code = (f"import sys, {modules};"
            "bad = sorted(m for m in sys.modules if m == 'textual' or m.startswith('textual.'));"
            "print(bad); sys.exit(1 if bad else 0)")
    python_prints(code)


def test_the_tui_loads_nothing_that_runs_a_launch():
    """An attached TUI speaks the vocabulary (engine/run/vocabulary/): importing it loads no
    module of the supervisor, of the processes, nor rclpy (lint-imports forbids the imports;
    this is what a user's process actually loads)."""
    code = ("import sys, tuilaunch.tui.app, tuilaunch.tui.fleet.app;"
            "bad = sorted(m for m in sys.modules if m.startswith(("
            "'tuilaunch.engine.run.supervisor', 'tuilaunch.engine.run.process', 'rclpy')));"
            "print(bad); sys.exit(1 if bad else 0)")
    assert python_prints(code).strip() == "[]"
