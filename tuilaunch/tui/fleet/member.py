"""One session of a fleet TUI (`tuilaunch attach a:x b:y`): its link, its tree, its pane.

Each member owns what the single-session TUI holds once for the app: a RemoteSupervisor on
the engine thread (its own ssh link, reconnected by itself), an EventBuffer its events
wait in, an OutputStore, and the widgets showing them (a LaunchTree whose root is the
session, an OutputPanel). Nothing is shared between members but the engine thread, so a
relaunch, a stop or a lost link of one touches nothing of another.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable, Coroutine
from dataclasses import dataclass, field
from typing import Any

from rich.text import Text

from ...client.link import relink_words
from ...client.port import LaunchPort
from ...client.served_session import ServedSession
from ...engine.plan.session import Session
from ...engine.run.event_buffer import EventBuffer
from ...engine.run.events import (
    Event,
    Reading,
    Relaunched,
)
from ..keys.keyboard import NodeKeyboard
from ..nodes.events import NodeEvents
from ..output_store import OutputStore
from ..screens.output_panel import OutputPanel
from ..screens.tree_panel import LaunchTree
from ..status_line import counts_words, silence_words


@dataclass(eq=False)
class Member:
    """A session of the fleet: `label` is how the tree names it (HOST:NAME, local:NAME)."""

    label: str
    host: str | None  # None: this computer
    name: str
    tree: LaunchTree
    pane: OutputPanel
    store: OutputStore
    session: Session = field(default_factory=lambda: ServedSession("?", {}))
    """Its plan: the one its server runs, sent over the link (a test hands its own)."""
    buffer: EventBuffer = field(default_factory=lambda: EventBuffer(max_lines=2500))
    supervisor: LaunchPort | None = None
    problem: str | None = None
    """Why the member is not followed now: cannot be reached (retrying), or ended."""
    ended: bool = False
    wake: asyncio.Event | None = None
    """Set by R: the next try to reach a session never reached, now."""
    asked_to_stop: set[str] = field(default_factory=set)
    on_event: Callable[[Member, Event], None] | None = None
    """Where the events for its tabs go (readings, relaunches): fleet/tabs.py."""
    events: NodeEvents = field(init=False)
    """How its events show in its tree and pane."""
    keyboard: NodeKeyboard = field(init=False)
    """`i`, `g`, `c` on its nodes: the single TUI's keyboard over this session (set with
    its host, fleet/tabs.py)."""

    def __post_init__(self) -> None:
        self.events = NodeEvents(
            self.tree, self.store, lambda: self.session.plan,
            lambda: None if self.supervisor is None else self.supervisor.states,
            lambda: {} if self.supervisor is None else self.supervisor.lifecycle.states,
            asked_to_stop=self.asked_to_stop)

    @property
    def address(self) -> str:
        """As the command line takes it."""
        return self.name if self.host is None else f"{self.host}:{self.name}"

    def unavailable(self) -> str | None:
        """Why keys cannot act on this session now (None: they can)."""
        if self.supervisor is None or self.ended:
            return self.problem or "not connected"
        return self.supervisor.link_lost

    def silence(self) -> str | None:
        """`no word from arm for 7 s`, as the single TUI's status line says it."""
        supervisor = self.supervisor
        return None if supervisor is None or self.ended else silence_words(supervisor)

    def counts_text(self) -> str:
        """Its processes by state, as the single TUI's status line counts them."""
        if self.supervisor is None:
            return ""
        return counts_words(self.session.plan, self.tree.states, self.supervisor.states)

    def root_label(self) -> Text:
        """The session's root row: its address and live counts; greyed, with why,
        while it cannot be reached."""
        label = Text(self.label, style="bold")  # its file is in the header: room for counts
        why = self.unavailable()
        if self.ended:
            label.append(f" {why}  {self.counts_text()}", "italic")
            label.stylize("dim")
        elif why is not None:
            # a link that dropped reconnects by itself (an attempt under way says so, with
            # the latest reason); one never made says it retries
            label.append(f" {why}" + (f"; {self._relinking(self.supervisor)}"
                                      if self.supervisor else ""), "italic")
            label.stylize("dim")
        elif self.silence() is not None:
            # what it shows may be old: said first, before the counts it last sent
            label.append(f" {self.silence()}", "bold yellow")
            label.append(f"  {self.counts_text()}")
        else:
            label.append(f"  {self.counts_text()}")
        return label

    @staticmethod
    def _relinking(port: LaunchPort) -> str:
        since = port.attempt_since
        words = relink_words(port.attempt, None if since is None else time.monotonic() - since)
        if words == "reconnecting":  # between tries (or one just begun): R tries now
            return "reconnecting (R: now)"
        last = port.lost_reason or ""
        return words + (f", last: {last}" if last and last not in (port.link_lost or "") else "")

    def tell_shown(self) -> Coroutine[Any, Any, None] | None:
        """The call telling the session whose lines its pane shows (all for all nodes),
        when it must be told: as the single TUI, only over a link (a session here sends
        its lines to a screen at its drain rate, which costs no link)."""
        supervisor = self.supervisor
        if supervisor is None or supervisor.host is None or self.ended or \
                supervisor.link_lost is not None:
            return None
        shown = self.pane.view.process
        return None if shown == supervisor.only else supervisor.show(shown)

    def refresh_root(self) -> None:
        label = self.root_label()
        if label.plain != str(self.tree.root.label):  # an unchanged row is not sent again
            self.tree.root.set_label(label)

    # --- events ------------------------------------------------------------------------------

    def show_events(self, events: list[Event]) -> None:
        """The events of a drain into this member's tree and pane, as the single TUI's
        Nodes tab shows them (the same NodeEvents); the readings and the relaunches to its
        tabs (`on_event`)."""
        kept = events
        events = self.keyboard.take_events(events)  # who types where: the keyboard's
        shown = self.events.show([e for e in events if not isinstance(e, Reading)])
        if self.on_event is not None:
            for event in events:
                if isinstance(event, (Reading, Relaunched)):
                    self.on_event(self, event)
        if shown.lines:
            self.pane.append(shown.lines)
        self.pane.flush()
        if shown.counting:  # a respawn's wait: its row counts down (only changed rows drawn)
            self.events.count_down()
        if events:
            self.refresh_root()
        self.keyboard.events_shown(kept)  # a node typed into that ended gives the keys back

    def show_plan(self) -> None:
        """The session's plan as the tree's children, its root the session."""
        self.events.show_plan()
        self.refresh_root()
