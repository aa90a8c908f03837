"""The TUI's recordings: the Topics tab's `w` records the selected topic into an MCAP file
on this computer (`w` again stops it), its header says so with the size so far; `b`
writes the session's black box now, in the session's log folder, and says where.

The recording is pulled from the session as `tuilaunch record` pulls it
(client/recording.py), on the UI's loop; the file is written on a thread.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from ...client.inspect.recording import LiveRecording
from ...engine.run.session.session_dir import SessionError
from ...engine.run.vocabulary.requests import BlackBox, BlackBoxWrite


class Recordings:
    """One recording at a time, and the black box's key, for an app; `inspect` asks its
    session."""

    def __init__(self, app: Any, inspect: Callable[[Any], Awaitable[Any]]) -> None:
        self.app = app
        self.inspect = inspect
        self.live: LiveRecording | None = None
        self.timer: Any = None

    def toggle(self, topic: str | None) -> None:
        if self.live is not None:
            self.live.stop()
            return
        if topic is None:
            return
        try:
            self.live = LiveRecording(self.inspect, self.app.session_name or "session",
                                      [topic])
        except OSError as exc:
            self.app.notify(str(exc), severity="error", title="record")
            return
        self.app.run_worker(self._run(self.live, topic), group="recording",
                            exit_on_error=False)
        self.timer = self.app.set_interval(1.0, lambda: self._show(topic))
        self._show(topic)

    def _show(self, topic: str) -> None:
        live = self.live
        text = "" if live is None else f"● REC {topic} {live.file.size / 1e6:.1f} MB"
        self.app.topics_panel.show_recording(text)

    async def _run(self, live: LiveRecording, topic: str) -> None:
        await live.run()
        self.live = None
        if self.timer is not None:
            self.timer.stop()
        self._show(topic)
        if live.error:
            self.app.notify(f"{live.error}; what came is in {live.file.path}",
                            severity="error", title="record")
        else:
            self.app.notify(live.file.summary(), title="recorded")

    async def black_box_keep(self) -> None:
        """The palette's "Black box: keep the last N s": asks the seconds (offering what it
        keeps now, 0 switches it off), then the request `tuilaunch record NAME
        --black-box-on S` sends, its bound in bytes kept as it is."""
        from ..screens.dialogs import PathScreen

        try:
            status = await self.inspect(BlackBox())  # how it is: its seconds offered
        except SessionError as exc:
            self.app.notify(str(exc).split(": ", 1)[-1], severity="error", title="black box")
            return
        now = f"{status['seconds']:g}" if status.get("on") else ""
        said = f"now the last {now} s" if now else "now off"
        answer = await self.app.push_screen_wait(PathScreen(
            f"Black box ({said}): keep the last how many seconds of every topic and line? "
            "0 switches it off", now or "30"))
        if answer is None:
            return
        try:
            seconds = float(answer)
        except ValueError:
            seconds = -1.0
        if not 0 <= seconds < float("inf"):
            self.app.notify(f"black box: '{answer}' is not a number of seconds (0: off)",
                            severity="warning")
            return
        fields: dict[str, Any] = {"seconds": seconds}
        if status.get("size"):
            fields["size"] = status["size"]  # the bound it has (--black-box-size) stays
        try:
            status = await self.inspect(BlackBox(**fields))
        except SessionError as exc:
            self.app.notify(str(exc).split(": ", 1)[-1], severity="error", title="black box")
            return
        self.app.notify(f"black box on: the last {status['seconds']:g} s of every topic and "
                        f"line (at most {status['size'] >> 20} MB); b writes it now"
                        if status.get("on") else "black box off", title="black box")

    async def black_box_now(self) -> None:
        try:
            written = await self.inspect(BlackBoxWrite())
        except SessionError as exc:
            self.app.notify(str(exc).split(": ", 1)[-1], severity="error", title="black box")
            return
        self.app.notify(f"{written['path']} ({written['messages']} messages)",
                        title="black box written")


__all__ = ["Recordings"]
