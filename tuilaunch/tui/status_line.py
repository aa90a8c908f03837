"""The status line of the single TUI: the session's name and file, its processes' counts,
the arguments it runs with, a lost or silent link, the stop under way; and what the
session says once (the plan's warnings, a relaunch by another client)."""

from __future__ import annotations

import time
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from rich.text import Text

from ..client.link import lost_link_line
from ..client.port import LaunchPort
from ..engine.plan.model import Plan
from .output_store import WARN, Line

if TYPE_CHECKING:  # the session view reads its words here; the link holds the view
    from .session_link import SessionLink

SILENCE_SHOWN = 5.0
"""Seconds without a word from the other side of a link (probed meanwhile) after which the
status line says how long: a hung link says nothing else for ssh's 15 s."""
WARNINGS_SHOWN = 3
"""The plan's warnings shown as toasts when the TUI opens; all are in the all nodes pane."""


class StatusLine:
    """The line over the tabs, drawn only when it changes (`drawn` is what it shows)."""

    def __init__(self, app: SessionLink) -> None:
        self.app = app
        self.drawn = ""

    def relaunched_elsewhere(self, arguments: list[str], edited: str | None,
                              replaying: bool) -> None:
        """Another operator applied new values, or an edited file (`edited`: which one):
        the form shows them, so an edit here starts from what runs, never silently reverts
        theirs."""
        self.app.args_tab.show_form()
        if not replaying:  # a relaunch before this client came is no news to it
            what = [f"{edited} changed"] if edited else []
            what += [" ".join(arguments)] if arguments else [] if edited else ["defaults"]
            self.app.notify(f"relaunched by another client: {'; '.join(what)}")
        self.app.refresh_bindings()

    def plan_warnings(self) -> None:
        """What the plan warns about (a mistyped argument, a missing parameter file), said
        in the TUI: printed before it took the screen, it would only be seen after quitting."""
        lines: list[Line] = []
        warnings = self.app.session.plan.warnings
        for warning in warnings:
            lines += self.app.store.add_event("launch", f"warning: {warning}", WARN)
        # to the operator who gave the values (an attached client finds them in the all
        # nodes pane, as `launch` lines);
        # a few at most: a column of toasts would hide the screen
        if self.app.owner:
            for warning in warnings[:WARNINGS_SHOWN]:
                self.app.notify(warning, title="warning", severity="warning", timeout=20)
            if len(warnings) > WARNINGS_SHOWN:
                self.app.notify(f"{len(warnings) - WARNINGS_SHOWN} more warnings: in the all "
                            "nodes pane (a)", severity="warning", timeout=20)
        if lines:
            self.app.nodes.show_lines(lines)

    def update(self) -> None:
        """The status line drawn again, if it changed."""
        if self.app.supervisor is None or self.app.ended_elsewhere is not None:
            return  # the line says the session ended elsewhere until the TUI leaves
        text = counts_words(self.app.session.plan, self.app.launch_tree.states,
                            self.app.supervisor.states)
        undeclared = self.app.session.undeclared()
        args = " ".join(f"{k}:={v}" for k, v in self.app.session.arguments.items()
                        if k not in undeclared)
        if undeclared:  # a typo applies nothing: said first (a narrow header cuts the
            # end), never listed with what applies
            args = f"not declared: {', '.join(undeclared)}  {args}"
        prefix = ""
        if self.app.quitting:
            still = self.app.view.running()
            prefix = f"stopping {', '.join(still)} ({self.signal_stage()})... " if still \
                else "stopped. "
        name = Path(self.app.session.plan.file).name
        where = f"{self.app.session_host}:" if self.app.session_host else ""
        read_only = " read-only" if self.app.read_only else ""
        name = f"[{where}{self.app.session_name}{read_only}] {name}"
        link = self.app.view.over_link()
        if link is not None and link.link_lost:
            # what is shown is as it was when the link dropped; the short form first, so
            # 80 columns show it whole, then the reason (the latest attempt's), its end
            # kept; an attempt under way says so, and how long it has taken
            since = link.attempt_since
            prefix = lost_link_line(
                link.host or "", self.app.session_name, link.lost_reason or "", link.attempt,
                None if since is None else time.monotonic() - since,
                self.app.status_bar.size.width or 78) + f"  {prefix}"
            name = Path(self.app.session.plan.file).name
        elif link is not None and silence_words(link) is not None:
            prefix = f"{silence_words(link)} · {prefix}"
        line = f"{prefix}{name}  {text}  {args}"
        # typing, another client typing: said first
        notes = self.app.keyboard.status_notes(link is not None and bool(link.link_lost))
        if notes:
            line = f"{'  '.join(notes)}  |  {line}"
        if line != self.drawn:  # an unchanged line is not sent to the terminal again
            self.drawn = line
            # cut with an ellipsis where it does not fit: something is left out, and seen so
            self.app.status_bar.update(Text(line) if notes else
                                       Text(line, no_wrap=True, overflow="ellipsis"))

    def signal_stage(self) -> str:
        """Where the SIGINT -> SIGTERM -> SIGKILL escalation is, from the timeouts of the
        processes still running (the file's or `sigterm_timeout:=`, else launch's 5 s: the
        server waits as long)."""
        if self.app.quit_started is None:
            return "SIGINT sent"
        sigterm, sigkill = self._escalation()
        elapsed = time.monotonic() - self.app.quit_started
        if elapsed < sigterm:
            return f"SIGINT sent, SIGTERM in {sigterm - elapsed:.0f} s; q: kill now"
        elapsed -= sigterm
        if elapsed < sigkill:
            return f"SIGTERM sent, SIGKILL in {sigkill - elapsed:.0f} s; q: kill now"
        return "SIGKILL sent"

    def _escalation(self) -> tuple[float, float]:
        still = set(self.app.view.running())
        waits = [(self.app.sigterm_timeout if p.sigterm_timeout is None else p.sigterm_timeout,
                  self.app.sigkill_timeout if p.sigkill_timeout is None else p.sigkill_timeout)
                 for p in self.app.session.plan.processes if p.id in still]
        return (max(w[0] for w in waits), max(w[1] for w in waits)) if waits else \
            (self.app.sigterm_timeout, self.app.sigkill_timeout)


COUNTED = ("running", "unknown", "pending", "stopping", "exited", "failed", "respawning",
           "skipped")
"""The states a session's counts say, in this order (unknown: placed on a machine whose
link is lost)."""


def counts_words(plan: Plan, shown: Mapping[str, str], states: Mapping[str, str]) -> str:
    """`5 running  1 failed`: a session's processes by state, as its tree shows them (else as
    its port says), on the single TUI's status line and on each fleet session's root."""
    counts: dict[str, int] = {}
    for proc in plan.processes:
        state = shown.get(proc.id) or states.get(proc.id, "pending")
        counts[state] = counts.get(state, 0) + 1
    return "  ".join(f"{counts[s]} {'waiting' if s == 'pending' else s}" for s in COUNTED
                     if counts.get(s))


def silence_words(port: LaunchPort) -> str | None:
    """`no word from arm for 7 s`: a link that has said nothing (probed meanwhile) for
    SILENCE_SHOWN s or more, on the single TUI's status line and on a fleet session's root;
    a hung link is said lost only after ssh's 15 s. None: no link, or it speaks."""
    if port.host is None:
        return None
    silent = port.silent_for()  # 0 while the link is down: its lost line says that
    return f"no word from {port.host} for {silent:.0f} s" if silent >= SILENCE_SHOWN else None
