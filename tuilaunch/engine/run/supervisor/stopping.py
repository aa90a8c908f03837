"""Stopping: SIGINT, then SIGTERM, then SIGKILL to each process group; shutdown; kill_all.

Each process leads its own process group; it is signalled as one. Each stage waits for the
process's own sigterm_timeout / sigkill_timeout; the operator can hurry it (`escalate_now`).
"""

from __future__ import annotations

import asyncio
import os
import signal
import time
from pathlib import Path
from typing import Any

from ..events import Event, LaunchEvent
from ..process.readers import Running
from .plan_actions import PlanActions

STAGES = (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
STOP_RACE = 2.0
"""Seconds before a stop within which a child's death by that stop's signal counts as part
of the stop (see Stopping.real_crashes)."""


class Stopping(PlanActions):
    """Stopping processes and the launch."""

    async def stop(self, process_id: str) -> None:
        running = self.running.get(process_id)
        if running is not None:
            running.stopping = True
            await self.escalate(running)

    async def shutdown(self, reason: str = "shutdown") -> None:
        if self.shutting_down:
            return
        self.shutting_down = True
        self.stop_time = time.monotonic()
        try:
            await self.tell_shutdown(reason)
        finally:
            for task in list(self.detached_tasks.values()):
                task.cancel()
            await asyncio.gather(*(self.escalate(r) for r in list(self.running.values())),
                                 return_exceptions=True)
            self.changed.set()

    async def tell_shutdown(self, reason: str) -> None:
        """The Shutdown event: said, and seen by the OnShutdown handlers. A Shutdown action
        performed while the launch already stops calls this again, as launch emits its
        event again (its handlers see both reasons)."""
        self.emit(Event("shutdown", reason=reason))
        for action in self.on_shutdown:
            try:
                await self.perform_action(action, LaunchEvent(reason=reason))
            except Exception as exc:  # an OnShutdown action never stops the shutdown
                self.report_io(f"on-shutdown action {action.id} raised "
                               f"{type(exc).__name__}: {exc}")

    def escalate_now(self) -> str | None:
        """The operator insists (a second Ctrl+C): SIGTERM now; once more: SIGKILL.

        Returns the signal's name now sent, or None when nothing is left to stop."""
        if not self.running:
            return None
        self.urgency = min(self.urgency + 1, len(STAGES) - 1)
        if self.hurry is not None:
            self.hurry.set()
        self.hurry = None
        if not self.shutting_down:
            self.spawn_task(self.shutdown("stop requested again"))
        return STAGES[self.urgency].name

    async def escalate(self, running: Running) -> None:
        """SIGINT, then SIGTERM, then SIGKILL, to the whole process group.

        The waits are the process's own sigterm_timeout / sigkill_timeout when it sets them;
        each step is announced; `escalate_now` skips the wait."""
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
            stage = max(stage, self.urgency if self.shutting_down else 0)
            if stage > sent:
                if stage > 0:
                    self.emit(Event("log", proc.id, level="WARN", reason=(
                        f"{why}sending {STAGES[stage].name} to its process group")))
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
                self.emit(Event("log", proc.id, level="ERROR", reason=(
                    f"still there {waits[stage]:g} s after SIGKILL (stuck in the kernel?); "
                    "no longer waiting for it")))
                return
            if self.urgency > stage and self.shutting_down:
                why = "asked again: "
            else:
                why = f"still running {waits[stage]:g} s after {STAGES[stage].name}: "
                stage += 1
        await asyncio.shield(running.exited)

    def kill_all(self) -> None:
        """Last resort when the caller cannot wait (the UI is being torn down): SIGKILL,
        and the watchdog sweeps what the processes left behind."""
        self.shutting_down = True
        for running in list(self.running.values()):
            kill_group(running.process.pid, signal.SIGKILL)
        self.remove_parameter_files()
        self.watchdog.close()

    def real_crashes(self) -> dict[str, int]:
        """Crashes, less the processes that died of the stop signal itself just before the
        stop was seen: a terminal's Ctrl+C or hang-up reaches a child that is still in
        tuilaunch's process group for the instant between its fork and its own session."""
        if self.stop_time is None:
            return self.crashes
        return {pid: code for pid, code in self.crashes.items()
                if not (-code in STOP_SIGNALS and
                        self.stop_time - self.crash_times[pid] < STOP_RACE)}

    def remove_parameter_files(self) -> None:
        for proc in self.plan.processes:
            for path, _ in proc.generated_parameter_files:
                Path(path).unlink(missing_ok=True)
        try:
            self.plan.params_dir.rmdir()
        except OSError:
            pass


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
