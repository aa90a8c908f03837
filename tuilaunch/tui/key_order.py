"""Keys are handled one after the other, each where the focus is once the key before it is done.

Textual forwards each key to the widget focused when the app reads it, then handles it
later, as it bubbles from that widget's message queue to the app, where the bindings run.
Keys that arrive in one read (over ssh, pasted, sent by tmux) are all forwarded before the
first of them has run: after `/` opens the search field, the `s` of `/set` had already
been sent to the tree, and reached the app's `s` binding (stop the node) instead of the
field. Here a key's trip is tracked, and the keys that arrive meanwhile wait; the next one
goes out once the trip is over and what it set in motion (a focus change, a dialog being
pushed, a field being mounted) has been processed, so it is sent to the widget that has
the focus then. An action that opens its field later (after a worker) holds the keys
until then (`hold_keys`). The private Textual names this needs are reached through
textual_compat.py, which lists them and why.
"""

from __future__ import annotations

import asyncio
import time
from collections import deque
from collections.abc import Callable, Iterable
from typing import Any

from textual import events
from textual.app import App
from textual.message_pump import MessagePump
from textual.widget import Widget

from .textual_compat import (
    TripKey,
    active_message_pump,
    character_to_key,
    has_messages,
    is_closing,
    send_as_app,
    xterm_parser,
)

# Textual reads ESC and a digit arriving in one read (esc then 3, typed fast over ssh or sent
# by tmux) as the character macOS's option key gives: in a field that is "leave, then 3"
ESC_DIGITS = {"¡": "1", "™": "2", "£": "3", "¢": "4", "∞": "5", "§": "6", "¶": "7",
              "•": "8", "ª": "9", "º": "0"}


def after_escape(event: events.Key) -> events.Key | None:
    """The key typed right after escape, when both came in one read: ESC and a digit read
    as the option-key character, ESC and another key as `alt+KEY` (no alt binding of ours
    or of Input's uses a printable key)."""
    character = event.character or ""
    if character in ESC_DIGITS:
        digit = ESC_DIGITS[character]
        return events.Key(digit, digit)
    if event.key.startswith("alt+") and len(character) == 1 and character.isprintable():
        return events.Key(character_to_key(character), character)
    return None


def keep_escape_before_punctuation() -> None:
    """Textual's terminal parser reads ESC and a letter in one read as `alt+LETTER`, but
    ESC and `/`, `:`, `\\` ... as the character alone: the escape is lost, and `esc /`
    typed fast in the search field types `/` into it. Here those come as `alt+slash` ...
    too, which the app splits into the two keys (after_escape)."""
    parser = xterm_parser()
    original = parser._sequence_to_key_events
    if getattr(original, "keeps_escape", False):
        return

    def sequence_to_key_events(self: Any, sequence: str, alt: bool = False)\
            -> Iterable[events.Key]:
        for key in original(self, sequence, alt):
            if alt and len(sequence) == 1 and key.character == sequence and \
                    sequence.isprintable() and not key.key.startswith("alt+"):
                yield events.Key(f"alt+{key.key}", key.character)
            else:
                yield key

    sequence_to_key_events.keeps_escape = True  # type: ignore[attr-defined]
    parser._sequence_to_key_events = sequence_to_key_events


BURST_GAP = 0.3
"""Seconds between two keys past which they are no longer one burst: a line typed as ssh
or tmux delivers it comes at once, a fast typist's keys a tenth of a second apart."""


class KeyHold:
    """The keys typed after an action, held until its field opens (`release`, or calling
    the hold), or dropped with the rest of their burst when it will not (`drop`). Either
    once: the first call counts."""

    def __init__(self, let_go: Callable[[bool, Callable[[], None] | None], None] | None
                 = None) -> None:
        self._let_go = let_go

    def __call__(self) -> None:
        self.release()

    def release(self) -> None:
        self._end(drop=False)

    def drop(self, said: Callable[[], None] | None = None) -> None:
        """Drops the keys held and the rest of their burst; `said` is called once, when a
        key was dropped (none typed with the action: nothing to say)."""
        self._end(drop=True, said=said)

    def _end(self, drop: bool, said: Callable[[], None] | None = None) -> None:
        let_go, self._let_go = self._let_go, None
        if let_go is not None:
            let_go(drop, said)


STUCK_AFTER = 15.0
"""Seconds after which a key whose trip never reported its end no longer holds the others
back: the keys go on as Textual sends them. A key whose widget was removed with it in its
queue is let go at the next look (`lost`), not after this. It was 3 s, but on a loaded
machine a legitimate trip came near it (the first show of the Services tab: 1.4 s with 8
busy processes on 2 cores), and a key let go early reaches the widget the one before it was
leaving (`s` on a node's row, where it was typed for a field about to open)."""

STUCK_CHECK = 0.75
"""Seconds between two looks at the key in flight while others wait."""


class TrackedKey(TripKey):
    """A key on its trip through the widgets; tells the app when the trip is over."""

    def __init__(self, key: str, character: str | None, done: Callable[[TrackedKey], None])\
            -> None:
        super().__init__(key, character)
        self._done = done
        self._finished = False
        self.holder: MessagePump | None = None
        """The widget (or screen, or app) whose queue the key is in, or that handles it."""

    def finish(self) -> None:
        if not self._finished:
            self._finished = True
            self._done(self)

    def stop(self, stop: bool = True) -> TrackedKey:
        super().stop(stop)
        if stop:  # its trip ends where it is handled, once the handler returns
            pump = active_message_pump.get(None)
            if pump is None:
                self.finish()
            else:
                pump.call_next(self.finish)
        return self

    def went_to(self, widget: MessagePump) -> None:
        self.holder = widget

    def forwarded(self) -> None:
        if self.holder is None:
            self.holder = forward_target(self)


TrackedKey.handler_name = "on_key"  # handled as the key it is: on_key, key_..., bindings


def forward_target(key: events.Key) -> MessagePump | None:
    app = active_message_pump.get(None)
    if isinstance(app, App):
        return app.focused or app.screen
    return None


class KeyOrder(App[int]):
    """The app's side: keys wait their turn; `reroute_key` puts a key back first in line."""

    def __init__(self, *args: Any, **options: Any) -> None:
        super().__init__(*args, **options)
        keep_escape_before_punctuation()
        self._key_in_flight: events.Key | events.Paste | None = None
        """The key on its trip, or the one released to go next (then not yet tracked)."""
        self._key_started = 0.0
        self._keys_waiting: deque[events.Key | events.Paste] = deque()
        self._first_in_line = 0
        """Where a rerouted key goes in the waiting line: after those rerouted by the same
        key, before the keys read after it."""
        self._key_holds = 0
        self._arrival = 0.0
        """When the key on its trip was read from the terminal (Textual stamps each event
        as it is made, in the driver's thread): bursts are told apart by these times, not
        by when the keys' turns come, which a busy loop delays."""
        self._stuck_timer: Any = None
        self._settling: asyncio.Task[None] | None = None
        self.dropping_until = 0.0
        """Until when (time.monotonic) a key read belongs to a burst being dropped
        (`_drop_burst`): a question `i` opened takes the keys typed after it."""
        self._say_dropped: Callable[[], None] | None = None
        """Says that the burst being dropped was: once, at its first key dropped."""

    async def on_event(self, event: events.Event) -> None:
        if not isinstance(event, (events.Key, events.Paste)):
            await super().on_event(event)
            return
        if not self.screen_stack:  # the app is ending: no widget left to take a key
            return
        if isinstance(event, events.Paste):
            await self._paste(event)
            return
        if event.is_forwarded:  # back at the app: its bindings run here, then the trip ends
            try:
                await super().on_event(event)
            finally:
                if isinstance(event, TrackedKey):
                    event.finish()
            return
        if self._dropped(event) or self._waits_its_turn(event):
            return
        following = after_escape(event)
        if following is not None:
            # ESC and the next key in one read (typed fast, over ssh, tmux) are parsed as
            # one alt-key: they are the two keys the user typed, escape first
            self._keys_waiting.appendleft(following)
            event = events.Key("escape", "\x1b")
        tracked = TrackedKey(event.key, event.character, self._key_done)
        tracked.time = event.time  # when it was read, not when its turn came
        self._arrival = event.time
        # no sender: a key sent by the app would stop at the screen, its trip ending
        # there before the app's bindings ran
        send_as_app(tracked)
        self._key_in_flight = tracked
        self._key_started = time.monotonic()
        self._first_in_line = 0
        try:
            await super().on_event(tracked)
        finally:
            if not tracked.is_forwarded:  # a priority binding took it, or nothing could
                tracked.finish()

    def _waits_its_turn(self, event: events.Key | events.Paste) -> bool:
        """Queues a key or a paste behind the one in flight, or behind those waiting or held:
        True when it waits."""
        if event is self._key_in_flight or (
                self._key_in_flight is None and not self._keys_waiting and not self._key_holds):
            return False
        self._keys_waiting.append(event)
        self._watch_stuck()
        return True

    async def _paste(self, paste: events.Paste) -> None:
        """Pasted text (one event, bracketed paste) takes its turn among the keys: `/` then
        a paste searches for the pasted text. It goes to the widget focused when its turn
        comes; its handling starts no trip of bindings to wait for."""
        if paste.is_forwarded:
            await super().on_event(paste)
            return
        if self._dropped(paste) or self._waits_its_turn(paste):
            return
        self._key_in_flight = None
        await super().on_event(paste)
        if self._keys_waiting:
            self._settling = asyncio.create_task(self._settle_then_next())

    def reroute_key(self, key: events.Key) -> None:
        """A key that reached a widget it was not meant for (a field the user has left,
        escape read together with the next key) goes out again, before the keys read
        after it."""
        if self._key_in_flight is None and not self._keys_waiting and not self._key_holds:
            self.post_message(key)
            return
        self._keys_waiting.insert(self._first_in_line, key)
        self._first_in_line += 1

    def hold_keys(self) -> KeyHold:
        """For an action whose field opens later (after a worker): the keys typed after it
        wait until the returned hold is released, so they reach that field; or are dropped
        (`KeyHold.drop`) when the field will not open, so that keys meant for a node never
        become tuilaunch's commands."""
        self._key_holds += 1
        # the burst to drop, if it comes to that, is the one of the key that took the hold
        since = self._arrival if self._key_in_flight is not None else time.monotonic()

        def let_go(drop: bool, said: Callable[[], None] | None = None) -> None:
            self._let_go(drop, said, since)

        return KeyHold(let_go)

    def _let_go(self, drop: bool, said: Callable[[], None] | None, since: float) -> None:
        self._key_holds = max(0, self._key_holds - 1)  # 0 already when it was stuck
        if drop:
            self._drop_burst(said, since)
        self._next_key()

    def _drop_burst(self, said: Callable[[], None] | None, since: float) -> None:
        """Drops the keys of the burst of the held action's key (read at `since`): those
        waiting and those still to come, until a pause of `BURST_GAP` between two keys as
        they were read, however late their turn comes. Keys typed after that pause are
        kept. `said` is called at the first key dropped."""
        if self._key_holds:
            return  # another hold still waits for its field: those keys are its
        self._say_dropped = said
        last = since
        kept: deque[events.Key | events.Paste] = deque()
        dropped = False
        for key in self._keys_waiting:
            if not kept and key.time - last < BURST_GAP:
                last, dropped = key.time, True
            else:
                kept.append(key)
        self._keys_waiting = kept
        if dropped:
            self._tell_dropped()
        self._first_in_line = 0
        self.dropping_until = last + BURST_GAP

    def _dropped(self, event: events.Key | events.Paste) -> bool:
        """A key of a burst being dropped: it goes nowhere, and the burst goes on."""
        if event.time >= self.dropping_until:
            self._say_dropped = None
            return False
        self.dropping_until = event.time + BURST_GAP
        self._tell_dropped()
        return True

    def _tell_dropped(self) -> None:
        said, self._say_dropped = self._say_dropped, None
        if said is not None:
            said()

    def _key_done(self, key: TrackedKey) -> None:
        if self._key_in_flight is not key:
            return
        self._key_in_flight = None
        if self._keys_waiting:
            # what this key set in motion is processed first: a focus change, a dialog
            self._settling = asyncio.create_task(self._settle_then_next())

    async def _settle_then_next(self) -> None:
        await settle(self)
        self._next_key()

    def _next_key(self) -> None:
        if self._key_in_flight is not None or self._key_holds or not self._keys_waiting:
            return
        key = self._keys_waiting.popleft()
        self._key_in_flight = key  # this one goes next; keys read meanwhile wait
        self._key_started = time.monotonic()
        self.post_message(key)

    def _watch_stuck(self) -> None:
        if self._stuck_timer is None:
            self._stuck_timer = self.set_timer(STUCK_CHECK, self._check_stuck)

    def _check_stuck(self) -> None:
        self._stuck_timer = None
        key = self._key_in_flight
        if key is None and not self._key_holds:
            self._next_key()
        elif key is not None and (lost(key) or
                                  time.monotonic() - self._key_started > STUCK_AFTER):
            self._key_in_flight = None
            self._next_key()
        elif self._key_holds and time.monotonic() - self._key_started > STUCK_AFTER * 2:
            self._key_holds = 0  # an action that never released them: the keys go on
            self._next_key()
        if self._keys_waiting:
            self._watch_stuck()


def lost(key: events.Event) -> bool:
    """The key is in the queue of a widget that is gone, and will never come back."""
    holder = key.holder if isinstance(key, TrackedKey) else None
    if holder is None:
        return False
    if is_closing(holder):
        return True
    return isinstance(holder, Widget) and not holder.is_attached


async def settle(app: App[Any]) -> None:
    """Returns once the app, the screen, the focused widget and every widget with messages
    waiting have processed what is in their queues now (as Pilot waits for the screen)."""
    try:
        screen = app.screen
    except Exception:
        return
    pumps: list[MessagePump] = [app, screen]
    if app.focused is not None:
        pumps.append(app.focused)
    pumps.extend(w for w in screen.walk_children(with_self=False)
                 if isinstance(w, MessagePump) and has_messages(w)
                 and w not in pumps)
    loop = asyncio.get_running_loop()
    waiting = []
    for pump in pumps:
        future = loop.create_future()
        if pump.call_later(lambda f=future: f.done() or f.set_result(None)):
            waiting.append(future)
    if waiting:
        await asyncio.wait(waiting, timeout=STUCK_AFTER)


def reroute_key(app: App[Any], key: events.Key) -> None:
    """Sends a key out again, first in line when the app orders its keys."""
    if isinstance(app, KeyOrder):
        app.reroute_key(key)
    else:
        app.post_message(key)


def hold_keys(app: App[Any]) -> KeyHold:
    """The keys typed from now on wait until the returned hold is released or dropped."""
    if isinstance(app, KeyOrder):
        return app.hold_keys()
    return KeyHold()
