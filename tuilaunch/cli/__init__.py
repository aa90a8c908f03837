"""The command line: the launcher (TUI, headless, detached) and the session commands."""

from __future__ import annotations

import os


def main(argv: list[str] | None = None) -> int:
    if argv is None and "_ARGCOMPLETE" in os.environ:
        # a Tab press in a shell that ran `tuilaunch completion bash`: answered, and the
        # process ends, before anything heavy is imported
        from .completion import complete

        complete()
    from .dispatch import main as run

    return run(argv)


__all__ = ["main"]
