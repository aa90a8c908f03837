"""The TUI's recordings: the Topics tab's `w` records the selected topic into an MCAP file
on this computer (`w` again stops it), its header says so with the size so far; `b`
writes the session's black box now, in the session's log folder, and says where.

The recording is pulled from the session as `tuilaunch record` pulls it
(client/recording.py), on the UI's loop; the file is written on a thread.
"""

from __future__ import annotations

from typing import Any

from ..client.recording import LiveRecording
from ..engine.run.session.session_dir import SessionError
from ..engine.run.vocabulary.requests import BlackBoxWrite


class Recordings:
    """One recording at a time, and the black box's key, for an app with `inspect`."""

    def __init__(self, app: Any) -> None:
        self.app = app
        self.live: LiveRecording | None = None
        self.timer: Any = None

    def toggle(self, topic: str | None) -> None:
        if self.live is not None:
            self.live.stop()
            return
        if topic is None:
            return
        try:
            self.live = LiveRecording(self.app.inspect, self.app.session_name or "session",
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

    async def black_box_now(self) -> None:
        try:
            written = await self.app.inspect(BlackBoxWrite())
        except SessionError as exc:
            self.app.notify(str(exc).split(": ", 1)[-1], severity="error", title="black box")
            return
        self.app.notify(f"{written['path']} ({written['messages']} messages)",
                        title="black box written")


__all__ = ["Recordings"]
