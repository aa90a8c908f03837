"""A share's events, states and lines shown on the launching side as its own processes'
are (machines_share.py's coordinator follows each share and hands it what it reads).

Each event of a process placed there is mirrored into the launching side's supervisor
(`Supervisor.mirror`), once (a new link repeats what the share keeps), its lines written to
this side's log file of the process too; what the link did not carry (before the first
link, or while it was down) is asked for from the share's log files and shown before the
events that follow. While a link is lost, none of its processes is shown running: their
state is `unknown` until it is back.
"""

from __future__ import annotations

from typing import Any

from ..events import LIVE_STATES, Dropped, Event, Log, Output, Typing
from ..process.logfiles import LogFile
from ..session.protocol import ProtocolError, event_from_dict
from ..supervisor.placed import UNKNOWN
from ..supervisor.supervisor import Supervisor
from ..vocabulary.requests import ShareLines
from ..vocabulary.text import screen_str
from .share_link import Share


class ShareMirror:
    """What the shares say of their processes, into the launching side's `supervisor`."""

    def __init__(self, supervisor: Supervisor) -> None:
        self.supervisor = supervisor

    def lost(self, share: Share, reason: str) -> None:
        """Its link is lost: what its processes do now is not known here (they may run on
        there, or end), so none is shown running; each says so until the link is back."""
        name = share.machine.name
        for proc in self.supervisor.plan.processes:
            state = self.supervisor.states.get(proc.id, "")
            if proc.machine == name and state in (*LIVE_STATES, "respawning"):
                share.unknown[proc.id] = state
                self.supervisor.mirror(Log(
                    proc.id, reason=f"state unknown until the link to {name} is back: "
                    f"{reason}", level="WARN",
                    data={"detail": f"(since the link to {name} was lost)"}), UNKNOWN)

    def back(self, share: Share) -> None:
        """Its link is back and its states known again: a process that ran on as it was
        says so (one that changed meanwhile was told by its events, just mirrored)."""
        unknown, share.unknown = share.unknown, {}
        pids = self.supervisor.core.placing.pids_elsewhere
        for process, before in unknown.items():
            state = self.supervisor.states.get(process)
            if state == UNKNOWN:  # the share did not say: as it was when the link dropped
                self.supervisor.states[process] = state = before
            if state == before:
                self.supervisor.mirror(Log(
                    process, reason=f"the link to {share.machine.name} is back: {state} "
                    "there", data={"detail": f"pid {pids[process]}" if process in pids and
                                   state in LIVE_STATES else ""}), state)

    def missed_lines(self, share: Share, offsets: dict[str, int]) -> list[ShareLines]:
        """What its processes printed before this subscription and was not seen here
        (before the first link, or while the link was down): the requests that ask for
        it, to be shown before the events that follow (held until then)."""
        asked = []
        for proc in self.supervisor.plan.processes:
            end = offsets.get(proc.id)
            if proc.machine != share.machine.name or end is None:
                continue
            start = share.offsets.get(proc.id, 0)
            share.offsets[proc.id] = end
            skip = share.received.pop(proc.id, 0)
            if end <= start:
                continue
            share.backfill.add(proc.id)
            asked.append(ShareLines(proc.id, start, end, skip))
        return asked

    def backfilled(self, share: Share, process: str, result: dict[str, Any]) -> None:
        skipped = int(result.get("skipped") or 0)
        if skipped:
            self.supervisor.log(f"{share.machine.name}: {skipped} earlier lines of {process} "
                                f"are only in its log file there", "WARN")
        for stamp, stream, text in result.get("lines") or []:
            event = Output(process, stream=str(stream),
                           lines=[screen_str(str(text))], time=float(stamp))
            self.log_output(share, event)
            self.supervisor.mirror(event)

    def events(self, share: Share, events: list[dict[str, Any]], touched: dict[str, str],
                states: dict[str, str] | None = None) -> None:
        mine = {p.id for p in self.supervisor.plan.processes
                if p.machine == share.machine.name}
        for data in events:
            try:
                event = event_from_dict(data)
            except (ProtocolError, TypeError):
                continue
            if event.process not in mine or isinstance(event, Typing):
                continue  # who types there is this side's to say (its client numbers)
            if isinstance(event, Output):
                if event.lines:  # not an unfinished line (a prompt), shown until it is whole
                    share.received[event.process] += len(event.lines)
                    self.log_output(share, event)
                self.supervisor.mirror(event)
                continue
            if isinstance(event, Dropped) and isinstance(event.code, int):
                # lines its queue let go: in the file, said by this event, not sent again
                share.received[event.process] += event.code
            key = (event.kind, event.process, event.pid, event.time)
            if key in share.seen:
                continue
            share.seen.add(key)
            self.supervisor.mirror(event, state_after(event))
        for process, state in {**(states or {}), **touched}.items():
            if process in mine and state != "elsewhere":
                self.supervisor.states[process] = state

    def log_output(self, share: Share, event: Event) -> None:
        """Its lines also go to this side's log file of the process, as local lines do."""
        assert event.process is not None
        log = share.logs.get(event.process)
        if log is None:
            path = self.supervisor.log_dir / f"{event.process}.log"
            try:
                log = share.logs[event.process] = LogFile(path, self.supervisor.log)
            except OSError:
                return
        stamp = f"{event.time:.6f} {event.stream or 'stdout'} ".encode()
        log.write(b"".join(stamp + line.encode(errors="replace") + b"\n"
                           for line in event.lines), len(event.lines))



def state_after(event: Event) -> str | None:
    """The state an event leaves its process in (the batch's states follow it)."""
    return {"started": "running", "stopping": "stopping", "exited": "exited",
            "failed": "failed", "respawning": "respawning"}.get(event.kind)


__all__ = ["ShareMirror", "state_after"]
