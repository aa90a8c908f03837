"""The Args tab of one session: its form, the preview of what the edits change, and the
relaunch (F5).

`ArgsTab` is a widget of its own that owns that state (the preview, the file's stamp), and
reaches its session through an `ArgsHost`: the single-session TUI is one, each session of
a fleet TUI (fleet/tabs.py) another, so both show the same tab, each for its session.
"""

from __future__ import annotations

from typing import Protocol

from textual import on, work
from textual.app import ComposeResult
from textual.containers import Vertical
from textual.timer import Timer

from ..engine.errors import LaunchError
from ..engine.plan.model import ArgumentInfo, PlanDiff
from ..engine.plan.session import Preview, Stamp, file_stamp
from .nodes.host import SessionParts
from .screens.args_panel import ArgsPanel, check_plan, check_values, type_notes
from .screens.tree_panel import LaunchTree


class ArgsHost(SessionParts, Protocol):
    """What the Args tab needs of whoever holds its session."""

    own_relaunch: list[str] | None
    """The arguments of this client's own relaunch, until the session says it happened."""

    @property
    def launch_tree(self) -> LaunchTree: ...

    def describe_waiting(self) -> None: ...

    def update_status(self) -> None: ...


class ArgsTab(Vertical):
    """The Args tab's edits: previewed against the plan as they are typed, applied (F5) as
    a relaunch of the host's session."""

    FILE_CHECK_S = 1.0
    """While the tab shows, the launch file's stamp is read this often: an edit saved
    meanwhile (or a syntax error fixed) is previewed without a key, so the tab never says
    "No change" or "no longer loads" about a file that is not the one on disk."""

    def __init__(self, host: ArgsHost, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.host = host
        self.preview: Preview | None = None
        self.file_timer: Timer | None = None
        self.file_seen: Stamp = None

    def compose(self) -> ComposeResult:
        plan = self.host.session.plan
        yield ArgsPanel(plan.arguments, plan.file, id="args-panel")

    @property
    def panel(self) -> ArgsPanel:
        return self.query_one(ArgsPanel)

    def show_form(self) -> None:
        """The form of the plan the session runs (a session's own, or a relaunch's, from
        another client or with an edited file): an edit starts from what runs."""
        self.preview = None
        self.host.launch_tree.set_preview(None)
        self.panel.show(self.host.session.plan.arguments)

    @on(ArgsPanel.Edited)
    def _args_edited(self, event: ArgsPanel.Edited) -> None:
        event.stop()
        if self.host.supervisor is not None:  # the form drawn before the session is followed
            self.preview_values(event.values)

    def preview_values(self, values: dict[str, str], reread: bool = False,
                       shown: bool = False) -> None:
        """What these form values would do; a value the plan cannot use is an error here,
        and F5 never applies it. The launch file is read again when it changed on disk
        (`reread`: whatever its stamp says, as F5 does), and what the edit changes is said.
        `shown`: the tab came on screen, nothing was typed."""
        host = self.host
        session = host.session
        previous = self.preview
        current = {a.name: a.value for a in session.plan.arguments}
        edits = {k: v for k, v in values.items() if v != current.get(k)}
        panel = self.panel
        tree = host.launch_tree
        # a value unlike its default's type, typed here or given on the command line, is
        # passed as written, as ros2 launch does: said (a slip is likely), never refused
        notes = "".join(f"Warning: {note} (passed as written); " for note in
                        type_notes(session.plan.arguments, values))
        running = {p for p, s in (host.supervisor.states.items() if host.supervisor else ())
                   if s == "running"}
        problem = check_values(session.plan.arguments, edits)
        if problem is None:
            self.preview = session.preview(edits, running, reread=reread)
            if self.preview.plan is not None:
                problem = check_plan(self.preview.plan)
        else:
            self.preview = Preview({**session.arguments, **edits}, None, None, problem)
        if problem is not None:
            self.preview = Preview(self.preview.arguments, None, None, problem)
        if self.preview.error is not None or self.preview.diff is None:
            tree.set_preview(None)
            error = self.preview.error or "the plan could not be made"
            panel.set_preview_text(f"Cannot apply: {error}" + (
                "; the launch runs on as it was" if "no longer loads" in error else ""),
                error=True)
        elif not edits and self.preview.file_changes is None:
            self.preview = None
            tree.set_preview(None)
            if notes or not (shown and previous is None):  # the hint stays until an edit
                panel.set_preview_text(notes + "No change from what runs now.", error=False)
        else:
            tree.set_preview(self.preview.diff)
            panel.set_preview_text(
                notes + _describe_diff(self.preview, session.plan.arguments), error=False)
        self.app.refresh_bindings()

    def set_shown(self, shown: bool) -> None:
        """The tab came on screen (the file may have been edited meanwhile: the preview
        says so before F5), or left it (the file is no longer watched)."""
        if shown and self.host.supervisor is not None:
            self.file_seen = file_stamp(self.host.session.path)
            self.preview_values(self.panel.values(), shown=True)
            if self.file_timer is None:
                self.file_timer = self.set_interval(self.FILE_CHECK_S, self._check_file,
                                                    pause=True)
            self.file_timer.resume()
        elif self.file_timer is not None:
            self.file_timer.pause()

    def _check_file(self) -> None:
        """The file changed on disk while the tab shows: the preview says so now."""
        stamp = file_stamp(self.host.session.path)
        if stamp != self.file_seen and self.host.supervisor is not None:
            self.file_seen = stamp
            self.preview_values(self.panel.values())

    @on(ArgsPanel.ApplyRequested)
    def _apply_requested(self, event: ArgsPanel.ApplyRequested) -> None:
        event.stop()
        self.apply()

    def apply(self) -> None:
        """F5: the form as it is now (keys typed just before F5 may not have been previewed
        yet), and the file as it is now, as a new ros2 launch would read it."""
        self.preview_values(self.panel.values(), reread=True)
        preview = self.preview
        if preview is None or preview.plan is None or preview.diff is None:
            error = "" if preview is None else str(preview.error)
            self.notify("nothing to apply" if preview is None else
                        f"cannot apply: {error}" + ("; the launch runs on as it was"
                                                    if "no longer loads" in error else ""),
                        severity="warning")
            return
        self.relaunch(preview)

    @work(group="relaunch", exclusive=True, exit_on_error=False)
    async def relaunch(self, preview: Preview) -> None:
        host = self.host
        assert host.supervisor is not None
        session = host.session
        saved = session.checkpoint()
        plan = session.accept(preview)
        host.own_relaunch = [f"{k}:={v}" for k, v in session.arguments.items()]
        try:
            diff = await host.engine.run(host.supervisor.replace_plan(plan))
        except LaunchError as exc:
            # the session refused (its file no longer loads there): nothing changed
            session.rollback(saved)
            host.own_relaunch = None
            message = str(exc).split(": cannot apply: ", 1)[-1]
            self.panel.set_preview_text(
                f"Not applied: {message}; the launch runs on as it was.", error=True)
            self.notify(message, title="relaunch refused", severity="error")
            return
        self.preview = None
        tree = host.launch_tree
        tree.set_preview(None)
        tree.show_plan(plan, host.supervisor.states)
        host.describe_waiting()
        # the values applied; the edited file's other arguments, a form of its own
        self.panel.show(plan.arguments)
        self.panel.set_preview_text(
            f"Applied. Stopped: {', '.join(diff.stop) or 'none'}; started: "
            f"{', '.join(diff.start) or 'none'}.", error=False)
        host.update_status()
        self.app.refresh_bindings()


def _describe_diff(preview: Preview, running: list[ArgumentInfo]) -> str:
    assert preview.diff is not None and preview.plan is not None
    text = ""
    edit = preview.file_changes
    if edit is not None:
        # what the edited file alone changes, with the values that run now; the form shows
        # the declarations that run until F5, so the edit's own are said here
        alters = "; ".join(part for part in (
            _declarations_words(running, preview.plan.arguments),
            _diff_words(edit, "adds", "changes", "removes")) if part)
        changed = f"{preview.edited or 'the launch file'} changed on disk"
        if not alters and preview.diff.empty:  # said once, not "no process changes" twice
            return f"{changed}: no process changes; F5 applies it anyway."
        text = f"{changed}: {alters or 'no process changes'}. "
    diff = preview.diff
    if diff.empty:
        return text + "No process changes; F5 applies the new values anyway."
    return text + _diff_words(diff, "would start", "would restart", "would stop") + \
        ".  F5 applies."


def _declarations_words(before: list[ArgumentInfo], after: list[ArgumentInfo]) -> str:
    """An edited file's argument declarations, against the running ones: `rate's default
    2.0 -> 5.0`, `declares loud`, `no longer declares mode`."""
    old = {a.name: a for a in before}
    new = {a.name: a for a in after}
    parts = [f"{name}'s default {old[name].default or 'none'} -> {new[name].default or 'none'}"
             for name in new if name in old and new[name].default != old[name].default]
    added = [name for name in new if name not in old]
    gone = [name for name in old if name not in new]
    if added:
        parts.append(f"declares {', '.join(added)}")
    if gone:
        parts.append(f"no longer declares {', '.join(gone)}")
    return "; ".join(parts)


def _diff_words(diff: PlanDiff, start: str, restart: str, stop: str) -> str:
    stop_only = [p for p in diff.stop if p not in diff.start]
    restarted = [p for p in diff.stop if p in diff.start]
    start_only = [p for p in diff.start if p not in diff.stop]
    parts = []
    if start_only:
        parts.append(f"{start}: {', '.join(start_only)}")
    if restarted:
        parts.append(f"{restart}: {', '.join(restarted)}")
    if stop_only:
        parts.append(f"{stop}: {', '.join(stop_only)}")
    return "; ".join(parts)
