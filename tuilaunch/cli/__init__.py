"""The command line: the launcher (TUI, headless, detached) and the session commands."""

from .dispatch import main

__all__ = ["main"]
