"""Leaving: quit (stopping every process), detach, kill now, SIGTERM and SIGHUP."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from .screens.dialogs import ConfirmScreen, QuitScreen
from .session_link import SessionLink


class Quitting(SessionLink):
    """Quit, detach, kill now; SIGTERM and SIGHUP. The supervisor worker exits the app once
    the shutdown it asked for is done."""

    def action_reconnect(self) -> None:
        """R: try the dropped link to the session's machine now, not at the next try."""
        supervisor = self.supervisor
        if supervisor is not None and supervisor.link_lost is not None:
            self.engine.call(supervisor.retry_now)
            self.notify(f"reconnecting to {supervisor.host}")
        else:
            self.notify("no link is down", severity="information")

    def action_request_quit(self) -> None:
        if self._asking_to_quit():
            return  # q or ctrl+c again while the question is shown: one question
        running = self.running()
        if (self.is_web or self.read_only) and not self.quitting:
            # a browser tab (tuilaunch serve) or a read-only view: q leaves, the launch
            # runs on, as closing the tab does
            self.action_detach()
            return
        if self.session_host is not None and not self.quitting:
            self._quit_remote(running)
            return
        if self.quitting:
            if running:
                self._offer_kill(running)
            return
        if not running:
            self.stop_all_and_exit()
            return

        def answered(answer: str | None) -> None:
            if answer == "stop":
                self.stop_all_and_exit()
            elif answer == "detach":
                self.action_detach()

        # a session runs on without this window: detaching is one of the answers
        self._ask_quit(QuitScreen(running, detach=True), answered)

    def _asking_to_quit(self) -> bool:
        return any(getattr(screen, "quit_question", False) for screen in self.screen_stack)

    def _ask_quit(self, screen: ConfirmScreen | QuitScreen, answered: Callable[[Any], None])\
            -> None:
        screen.quit_question = True
        self.push_screen(screen, answered)

    def _quit_remote(self, running: list[str]) -> None:
        """On another machine's session, quitting leaves it running unless the operator
        says to stop it: a robot's launch is not stopped by closing a laptop's TUI. With
        the link down nothing can be asked of it, so it is left as it is."""
        supervisor = self.supervisor
        if not running or (supervisor is not None and supervisor.link_lost is not None):
            self.action_detach()
            return

        def answered(answer: str | None) -> None:
            if answer == "stop":
                self.stop_all_and_exit()
            elif answer == "detach":
                self.action_detach()

        # the local question's keys: `n` keeps running here too, `d` detaches
        self._ask_quit(QuitScreen(running, detach=True, host=self.session_host), answered)

    async def action_quit(self) -> None:
        self.action_request_quit()

    def _offer_kill(self, running: list[str]) -> None:
        """A second q while stubborn processes stop: SIGKILL them now, or keep waiting."""
        def answered(yes: bool | None) -> None:
            if yes and self.supervisor is not None:
                self.kill_all()

        self._ask_quit(ConfirmScreen(
            f"Still stopping: {', '.join(running[:6])} ({self.signal_stage()}).\n"
            "Kill them now with SIGKILL?", "Kill now (y)", "Keep waiting (n)"), answered)

    def terminal_hung_up(self) -> None:
        """SIGHUP: the ssh session or tmux pane is gone. An attached session, or one started
        with --keep-on-hangup, runs on; otherwise everything stops, then the app leaves. The
        server does the stopping, so the launch is never left half-stopped."""
        self.terminal_lost = True
        if self.keep_on_hangup or not self.owner:
            self.action_detach()
        else:
            self.stop_all_and_exit("the terminal hung up (SIGHUP)")

    def terminated(self) -> None:
        """SIGTERM stops what this app started; a client that only attached just leaves."""
        if not self.owner:
            self.action_detach()
        else:
            # as ros2 launch, whose run is cancelled: the exit status says it did not end
            # on its own, and the shell is told why (report_end)
            self.signalled = "SIGTERM"
            self.stop_all_and_exit("SIGTERM")

    def action_detach(self) -> None:
        """Leaves the session running; the supervisor worker then exits the app."""
        if self.supervisor is None:  # not following the session yet: nothing to leave
            return
        self.detached = True
        self.run_worker(self.engine.run(self.supervisor.detach()), group="shutdown",
                        exit_on_error=False)

    def stop_all_and_exit(self, reason: str = "quit from the UI") -> None:
        """Shutdown escalation runs; the supervisor worker exits the app when all are gone.
        The reason goes into launch.log, so a stop nobody asked for at the keyboard is told
        apart later."""
        if self.supervisor is None:
            self.abandon_start()  # its server, if it is coming up, stops at once
            self.exit(1 if self.signalled else 0)
            return
        self.quitting = True
        self.quit_started = time.monotonic()
        self.update_status()
        self.run_worker(self.engine.run(self.supervisor.shutdown(reason)),
                        group="shutdown", exit_on_error=False)
