"""`L` on a node: its ROS log level, set while it runs through its logger service, or, for
a node without one, a restart at that level (offered first). One object per session a TUI
shows (the single TUI's, each session of a fleet's), which owns the level last set per
process, where the dialog starts."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from textual.app import App

from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.requests import LogLevel, Restart
from ..screens.dialogs import ChoiceScreen, ConfirmScreen

LEVELS = ["debug", "info", "warn", "error", "fatal"]


class LogLevels:
    """`request(request)` asks the session (raises SessionError with why); `said`
    starts each line (a fleet's session label); a stop it causes is noted in
    `asked_to_stop`, so the restart is not taken for a crash."""

    def __init__(self, app: App[Any], request: Callable[..., Awaitable[Any]],
                 asked_to_stop: set[str], said: str = "") -> None:
        self.app = app
        self.request = request
        self.asked_to_stop = asked_to_stop
        self.said = said
        self.levels: dict[str, str] = {}
        """The level last set per process (the dialog starts there)."""

    def ask(self, process: str, node: str) -> None:
        """The dialog for `process` (whose node is `node`), then the level set."""
        def answered(level: str | None) -> None:
            if level:
                self.app.run_worker(self._set(process, node, level), group="inspector",
                                    exit_on_error=False)

        self.app.push_screen(ChoiceScreen(f"{self.said}Log level of {node} ({process}):",
                                          LEVELS, self.levels.get(process, "info")), answered)

    async def _set(self, process: str, node: str, level: str) -> None:
        try:
            await self.request(LogLevel(node=node, level=level))
        except SessionError as exc:
            message = str(exc).split(": ", 1)[-1]
            if "logger service" not in message:
                self.app.notify(f"{self.said}{message}", severity="error", title="log level")
                return

            def answered(yes: bool | None) -> None:
                if yes:
                    self.app.run_worker(self._restart_at(process, level), group="inspector",
                                        exit_on_error=False)

            self.app.push_screen(ConfirmScreen(
                f"{self.said}{node} has no logger service (enable_logger_service), so its "
                f"level cannot change while it runs.\nRestart {process} with --log-level "
                f"{level}? (kept across its respawns)", "Restart (y)"), answered)
            return
        self.levels[process] = level
        self.app.notify(f"{self.said}{node}: log level {level}", title="log level")

    async def _restart_at(self, process: str, level: str) -> None:
        self.asked_to_stop.add(process)
        try:
            await self.request(Restart(process=process, log_level=level))
        except SessionError as exc:
            self.asked_to_stop.discard(process)
            self.app.notify(f"{self.said}{exc}", severity="error", title="restart")
            return
        self.levels[process] = level
        self.app.notify(f"{self.said}{process} restarted with --log-level {level}",
                        title="log level")
