"""What a client shows first: log lines and state events, as one history in time order."""

from __future__ import annotations

from typing import Any

from ..engine.run.events import Event, Output
from ..engine.run.session.log_reader import LogLine
from ..engine.run.session.protocol import event_from_dict
from ..engine.run.vocabulary.text import screen_str


def merged(lines: dict[str, list[LogLine]], recent: list[dict[str, Any]]) -> list[Event]:
    """Log lines of several processes and state events as one history, in time order."""
    timed: list[tuple[float, int, Event]] = []
    for process, found in lines.items():
        for line in found:
            timed.append((line.time, len(timed), Output(
                process, stream=line.stream, lines=[screen_str(line.text)], time=line.time)))
    for data in recent:
        event = event_from_dict(data)
        timed.append((event.time, len(timed), event))
    timed.sort(key=lambda item: (item[0], item[1]))
    return batched([event for _, _, event in timed])


def batched(events: list[Event]) -> list[Event]:
    """Consecutive output lines of one process and stream as one event."""
    out: list[Event] = []
    for event in events:
        last = out[-1] if out else None
        if (isinstance(event, Output) and last is not None and isinstance(last, Output)
                and last.process == event.process and last.stream == event.stream
                and event.lines and last.data is None):
            last.lines.append(*event.lines)
        else:
            out.append(event)
    return out
