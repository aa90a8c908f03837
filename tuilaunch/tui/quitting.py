"""Leaving: quit (stopping every process), detach, kill now, SIGTERM and SIGHUP."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from textual.binding import Binding

from .screens.dialogs import ConfirmScreen, QuitScreen
from .session_link import SessionLink

LEAVING_BINDINGS = [
    Binding("d", "leaving('detach')", "Detach", tooltip="Leave the launch running; "
            "tuilaunch attach opens it again"),
    Binding("R", "leaving('reconnect')", "Reconnect", show=False,
            tooltip="Reconnect a dropped link to the session's machine now"),
]
QUIT_BINDINGS = [
    Binding("q", "leaving('request_quit')", "Quit"),
    Binding("ctrl+c", "leaving('request_quit')", "Quit", show=False, priority=True),
]
"""The keys that leave, bound on the app (`action_leaving` hands them over by name)."""


class Quitting:
    """Quit, detach, kill now; SIGTERM and SIGHUP: an object the app holds (`app.leaving`).
    The supervisor worker exits the app once the shutdown it asked for is done."""

    def __init__(self, app: SessionLink) -> None:
        self.app = app

    def act(self, action: str) -> None:
        {"detach": self.detach, "reconnect": self.reconnect,
         "request_quit": self.request_quit}[action]()

    def reconnect(self) -> None:
        """R: try the dropped link to the session's machine now, not at the next try."""
        supervisor = self.app.supervisor
        if supervisor is not None and supervisor.link_lost is not None:
            self.app.engine.call(supervisor.retry_now)
            self.app.notify(f"reconnecting to {supervisor.host}")
        else:
            self.app.notify("no link is down", severity="information")

    def request_quit(self) -> None:
        if self._asking_to_quit():
            return  # q or ctrl+c again while the question is shown: one question
        running = self.app.view.running()
        if (self.app.is_web or self.app.read_only) and not self.app.quitting:
            # a browser tab (tuilaunch serve) or a read-only view: q leaves, the launch
            # runs on, as closing the tab does
            self.detach()
            return
        if self.app.session_host is not None and not self.app.quitting:
            self._quit_remote(running)
            return
        if self.app.quitting:
            if running:
                self._offer_kill(running)
            return
        if not running:
            self.stop_all_and_exit()
            return
        # a session runs on without this window: detaching is one of the answers
        self._ask_stop_or_detach(QuitScreen(running, detach=True))

    def _asking_to_quit(self) -> bool:
        return any(getattr(screen, "quit_question", False) for screen in self.app.screen_stack)

    def _ask_quit(self, screen: ConfirmScreen | QuitScreen, answered: Callable[[Any], None])\
            -> None:
        screen.quit_question = True
        self.app.push_screen(screen, answered)

    def _ask_stop_or_detach(self, screen: QuitScreen) -> None:
        def answered(answer: str | None) -> None:
            if answer == "stop":
                self.stop_all_and_exit()
            elif answer == "detach":
                self.detach()

        self._ask_quit(screen, answered)

    def _quit_remote(self, running: list[str]) -> None:
        """On another machine's session, quitting leaves it running unless the operator
        says to stop it: a robot's launch is not stopped by closing a laptop's TUI. With
        the link down nothing can be asked of it, so it is left as it is."""
        supervisor = self.app.supervisor
        if not running or (supervisor is not None and supervisor.link_lost is not None):
            self.detach()
            return
        # the local question's keys: `n` keeps running here too, `d` detaches
        self._ask_stop_or_detach(QuitScreen(running, detach=True, host=self.app.session_host))

    def _offer_kill(self, running: list[str]) -> None:
        """A second q while stubborn processes stop: SIGKILL them now, or keep waiting."""
        def answered(yes: bool | None) -> None:
            if yes and self.app.supervisor is not None:
                self.kill_all()

        self._ask_quit(ConfirmScreen(
            f"Still stopping: {', '.join(running[:6])} ({self.app.status.signal_stage()}).\n"
            "Kill them now with SIGKILL?", "Kill now (y)", "Keep waiting (n)"), answered)

    def terminal_hung_up(self) -> None:
        """SIGHUP: the ssh session or tmux pane is gone. An attached session, or one started
        with --keep-on-hangup, runs on; otherwise everything stops, then the app leaves. The
        server does the stopping, so the launch is never left half-stopped."""
        self.app.terminal_lost = True
        if self.app.keep_on_hangup or not self.app.owner:
            self.detach()
        else:
            self.stop_all_and_exit("the terminal hung up (SIGHUP)")

    def terminated(self) -> None:
        """SIGTERM stops what this app started; a client that only attached just leaves."""
        if not self.app.owner:
            self.detach()
        else:
            # as ros2 launch, whose run is cancelled: the exit status says it did not end
            # on its own, and the shell is told why (report_end)
            self.app.signalled = "SIGTERM"
            self.stop_all_and_exit("SIGTERM")

    def detach(self) -> None:
        """Leaves the session running; the supervisor worker then exits the app."""
        if self.app.supervisor is None:  # not following the session yet: nothing to leave
            return
        self.app.detached = True
        self.app.run_worker(self.app.engine.run(self.app.supervisor.detach()), group="shutdown",
                        exit_on_error=False)

    def stop_all_and_exit(self, reason: str = "quit from the UI") -> None:
        """Shutdown escalation runs; the supervisor worker exits the app when all are gone.
        The reason goes into launch.log, so a stop nobody asked for at the keyboard is told
        apart later."""
        if self.app.supervisor is None:
            if self.app.starting is not None:  # its server, if coming up, stops at once
                self.app.starting.abandon()
            self.app.exit(1 if self.app.signalled else 0)
            return
        self.app.quitting = True
        self.app.quit_started = time.monotonic()
        self.app.update_status()
        self.app.run_worker(self.app.engine.run(self.app.supervisor.shutdown(reason)),
                        group="shutdown", exit_on_error=False)

    def kill_all(self) -> None:
        """SIGKILL what is left, on the engine's thread: the supervisor (its process table,
        its watchdog pipe) belongs to that thread while its loop runs."""
        supervisor, engine = self.app.supervisor, self.app.engine
        assert supervisor is not None
        if engine.loop.is_running():
            try:
                engine.call(supervisor.kill_all)
                return
            except Exception:
                pass  # the loop ended meanwhile: nothing runs there any more
        supervisor.kill_all()
