"""Stopping: SIGINT, then SIGTERM, then SIGKILL to each process group.

Each process leads its own process group; it is signalled as one. Each stage waits for the
process's own sigterm_timeout / sigkill_timeout; the operator can hurry it
(`Supervisor.escalate_now` -> `Stopper.insist`). The `Stopper` owns the escalation's state
and is made and tested alone (tests/integration/test_supervisor_parts.py); `Ending`'s `stop`,
`shutdown` and `kill_all` (run/supervisor/ending.py) use it.
"""

from __future__ import annotations

import asyncio
import os
import signal
import time
from collections.abc import Callable
from typing import Any

from ..events import Event, Log
from ..process.readers import Running

STAGES = (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
CTRL_C_REASON = "ctrl-c (SIGINT)"
"""launch's shutdown reason for Ctrl+C (launch_service.py's SIGINT handler)."""
STOP_RACE = 2.0
"""Seconds before a stop within which a child's death by that stop's signal counts as part
of the stop (see Stopper.real_crashes)."""


class Stopper:
    """The stop escalation: the signal each stopping process has reached, how hard the
    shutdown stops (`urgency`) and when it began. It signals process groups and says each
    step through `say`; `in_shutdown` tells it whether the launch is stopping."""

    def __init__(self, sigterm_timeout: float, sigkill_timeout: float,
                 say: Callable[[Event], None], in_shutdown: Callable[[], bool]) -> None:
        self.sigterm_timeout = sigterm_timeout
        self.sigkill_timeout = sigkill_timeout
        self._say = say
        self._in_shutdown = in_shutdown
        self.urgency = 0
        """How hard the shutdown stops: 0 SIGINT first; 1 SIGTERM now; 2 SIGKILL now."""
        self.hurry: asyncio.Event | None = None
        """Set to make the escalations skip to the urgency asked for."""
        self.stop_time: float | None = None
        """When the shutdown began (loop time), for its escalation deadlines."""
        self.terminal_sigint = False
        """The shutdown comes from Ctrl+C: as in launch, the SIGINT each process gets then
        is not announced (a terminal's Ctrl+C is the user's own, and seen)."""

    def began(self) -> None:
        """The launch's shutdown begins now."""
        self.stop_time = time.monotonic()

    def at_least(self, urgency: int) -> None:
        """Stop at least this hard from now on (1: SIGTERM first, 2: SIGKILL)."""
        self.urgency = max(self.urgency, urgency)

    def insist(self) -> str:
        """The operator insists: the next signal now; returns its name."""
        self.urgency = min(self.urgency + 1, len(STAGES) - 1)
        if self.hurry is not None:
            self.hurry.set()
        self.hurry = None
        return STAGES[self.urgency].name

    async def escalate(self, running: Running) -> None:
        """SIGINT, then SIGTERM, then SIGKILL, to the whole process group.

        The waits are the process's own sigterm_timeout / sigkill_timeout when it sets them;
        each step is announced; `insist` skips the wait."""
        running.stopping = True
        proc = running.plan
        waits = (proc.sigterm_timeout if proc.sigterm_timeout is not None
                 else self.sigterm_timeout,
                 proc.sigkill_timeout if proc.sigkill_timeout is not None
                 else self.sigkill_timeout, 10.0)
        sent = -1
        stage = 0
        why = ""
        while not running.exited.done():
            stage = max(stage, self.urgency if self._in_shutdown() else 0)
            if stage > sent:
                self._announce(proc.id, stage, why, waits)
                if not kill_group(running.process.pid, STAGES[stage]):
                    break  # the whole group is gone; the exit arrives through the pidfd
                sent = stage
            if self.hurry is None:
                self.hurry = asyncio.Event()
            hurry: asyncio.Future[Any] = asyncio.ensure_future(self.hurry.wait())
            exited: asyncio.Future[Any] = running.exited
            try:
                await asyncio.wait([exited, hurry], timeout=waits[stage],
                                   return_when=asyncio.FIRST_COMPLETED)
            finally:
                hurry.cancel()
            if running.exited.done():
                break
            if stage == len(STAGES) - 1:
                self._say(Log(proc.id, level="ERROR", reason=(
                    f"still there {waits[stage]:g} s after SIGKILL (stuck in the kernel?); "
                    "no longer waiting for it")))
                return
            if self.urgency > stage and self._in_shutdown():
                why = "asked again"
            else:
                why = "timeout"
                stage += 1
        await asyncio.shield(running.exited)

    def _announce(self, name: str, stage: int, why: str, waits: tuple[float, ...]) -> None:
        """Each signal in launch's words (ExecuteLocal), which people grep for: the timeout
        as an ERROR `failed to terminate ... escalating to`, then `sending signal`."""
        signal_name = STAGES[stage].name
        if why == "timeout":
            self._say(Log(name, level="ERROR", reason=(
                f"process[{name}] failed to terminate '{waits[stage - 1]:g}' seconds after "
                f"receiving '{STAGES[stage - 1].name}', escalating to '{signal_name}'")))
        elif why:  # the operator insisted (a second Ctrl+C, q, `stop` again)
            self._say(Log(name, level="WARN", reason=(
                f"asked again: sending signal '{signal_name}' to process[{name}]")))
            return
        elif self.terminal_sigint and self._in_shutdown():
            return
        self._say(Log(name, reason=f"sending signal '{signal_name}' to "
                      f"process[{name}]"))

    def real_crashes(self, crashes: dict[str, int],
                     crash_times: dict[str, float]) -> dict[str, int]:
        """Crashes, less the processes that died of the stop signal itself just before the
        stop was seen: a terminal's Ctrl+C or hang-up reaches a child that is still in
        tuilaunch's process group for the instant between its fork and its own session."""
        if self.stop_time is None:
            return crashes
        return {pid: code for pid, code in crashes.items()
                if not (-code in STOP_SIGNALS and
                        self.stop_time - crash_times[pid] < STOP_RACE)}


def kill_group(pgid: int, sig: signal.Signals) -> bool:
    try:
        os.killpg(pgid, sig)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True  # a member changed user (sudo in a wrapper): the others got it
    return True


def group_alive(pgid: int) -> bool:
    try:
        os.killpg(pgid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def describe_exit(code: int) -> str:
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"
