"""Editing launch arguments: the preview of what they would change, and the relaunch."""

from __future__ import annotations

from textual import on, work

from ..engine.plan.session import Preview
from .screens.args_panel import ArgsPanel, check_plan, check_values
from .session_link import SessionLink


class Arguments(SessionLink):
    """The Args tab's edits: previewed against the plan as they are typed, applied (F5) as a
    relaunch."""

    @on(ArgsPanel.Edited)
    def _args_edited(self, event: ArgsPanel.Edited) -> None:
        self.preview_values(event.values)

    def preview_values(self, values: dict[str, str]) -> None:
        """What these form values would do; a value the plan cannot use is an error here,
        and F5 never applies it."""
        current = {a.name: a.value for a in self.session.plan.arguments}
        edits = {k: v for k, v in values.items() if v != current.get(k)}
        panel = self.args_panel
        tree = self.launch_tree
        if not edits:
            self.preview = None
            tree.set_preview(None)
            panel.set_preview_text("No change from what runs now.", error=False)
            self.refresh_bindings()
            return
        running = {p for p, s in (self.supervisor.states.items() if self.supervisor else ())
                   if s == "running"}
        problem = check_values(self.session.plan.arguments, edits)
        if problem is None:
            self.preview = self.session.preview(edits, running)
            if self.preview.plan is not None:
                problem = check_plan(self.preview.plan)
        else:
            self.preview = Preview({**self.session.arguments, **edits}, None, None, problem)
        if problem is not None:
            self.preview = Preview(self.preview.arguments, None, None, problem)
        if self.preview.error is not None or self.preview.diff is None:
            tree.set_preview(None)
            panel.set_preview_text(f"Cannot apply: {self.preview.error}", error=True)
        else:
            tree.set_preview(self.preview.diff)
            panel.set_preview_text(_describe_diff(self.preview), error=False)
        self.refresh_bindings()

    @on(ArgsPanel.ApplyRequested)
    def _apply_requested(self) -> None:
        self.action_apply()

    def action_apply(self) -> None:
        # the form as it is now: keys typed just before F5 may not have been previewed yet
        self.preview_values(self.args_panel.values())
        preview = self.preview
        if preview is None or preview.plan is None or preview.diff is None:
            self.notify("nothing to apply" if preview is None else
                        f"cannot apply: {preview.error}", severity="warning")
            return
        self.relaunch(preview)

    @work(group="relaunch", exclusive=True, exit_on_error=False)
    async def relaunch(self, preview: Preview) -> None:
        assert self.supervisor is not None
        plan = self.session.accept(preview)
        self.own_relaunch = [f"{k}:={v}" for k, v in self.session.arguments.items()]
        diff = await self.engine.run(self.supervisor.replace_plan(plan))
        self.preview = None
        tree = self.launch_tree
        tree.set_preview(None)
        tree.show_plan(plan, self.supervisor.states)
        self.describe_waiting()
        self.args_panel.set_preview_text(
            f"Applied. Stopped: {', '.join(diff.stop) or 'none'}; started: "
            f"{', '.join(diff.start) or 'none'}.", error=False)
        self.update_status()
        self.refresh_bindings()


def _describe_diff(preview: Preview) -> str:
    assert preview.diff is not None and preview.plan is not None
    diff = preview.diff
    if diff.empty:
        return "No process changes; F5 applies the new values anyway."
    stop_only = [p for p in diff.stop if p not in diff.start]
    restart = [p for p in diff.stop if p in diff.start]
    start_only = [p for p in diff.start if p not in diff.stop]
    parts = []
    if start_only:
        parts.append(f"would start: {', '.join(start_only)}")
    if restart:
        parts.append(f"would restart: {', '.join(restart)}")
    if stop_only:
        parts.append(f"would stop: {', '.join(stop_only)}")
    return "; ".join(parts) + ".  F5 applies."
