"""`--headless`: run the plan and print every line as `[id] line`, like ros2 launch."""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import time
from pathlib import Path
from typing import TextIO

from .engine.plan.model import Plan
from .engine.run.output import strip_ansi
from .engine.run.supervisor import Event, Supervisor


def run_log_dir() -> Path:
    base = os.environ.get("ROS_LOG_DIR") or os.path.join(
        os.environ.get("ROS_HOME") or os.path.expanduser("~/.ros"), "log")
    stamp = time.strftime("%Y-%m-%d-%H-%M-%S")
    return Path(base) / f"{stamp}-tuilaunch-{os.getpid()}"


class Printer:
    """Writes events to a stream; strips colour codes unless the stream is a terminal."""

    def __init__(self, out: TextIO) -> None:
        self.out = out
        self.colour = out.isatty() and not os.environ.get("NO_COLOR")

    def __call__(self, event: Event) -> None:
        if event.kind == "output":
            prefix = f"[{event.process}] "
            text = "".join(prefix + (line if self.colour else strip_ansi(line)) + "\n"
                           for line in event.lines)
        elif event.kind in ("started", "finished") and event.pid is None:
            return  # an action's progress: its log lines already say what happened
        elif event.kind == "started":
            text = f"[INFO] [{event.process}]: process started with pid [{event.pid}]\n"
        elif event.kind == "exited":
            level = "INFO" if event.code == 0 else "ERROR"
            text = f"[{level}] [{event.process}]: process has finished ({event.reason})\n"
        elif event.kind == "failed":
            text = f"[ERROR] [{event.process}]: failed to start: {event.reason}\n"
        elif event.kind == "respawning":
            text = f"[WARN] [{event.process}]: respawning ({event.reason})\n"
        elif event.kind == "lifecycle":
            if not event.reason:
                return
            text = f"[INFO] [{event.process}]: lifecycle state {event.reason}\n"
        elif event.kind == "component":
            if event.data and event.data.get("state") == "loading":
                return  # "waiting for the service": the result line follows
            text = f"[{event.level}] [{event.process}]: {event.reason}\n"
        elif event.kind == "log":
            text = f"[{event.level}] [{event.process or 'launch.user'}]: {event.reason}\n"
        else:
            text = f"[INFO] [launch]: {event.kind} ({event.reason})\n"
        self.out.write(text)
        self.out.flush()


async def _run(plan: Plan, log_dir: Path) -> int:
    supervisor = Supervisor(plan, log_dir)
    supervisor.subscribe(Printer(sys.stdout))
    loop = asyncio.get_running_loop()

    stopping: set[asyncio.Task[None]] = set()  # held so the task is not collected mid-run

    def on_signal(sig: signal.Signals) -> None:
        stopping.add(asyncio.ensure_future(supervisor.shutdown(f"received {sig.name}")))

    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        loop.add_signal_handler(sig, on_signal, sig)
    print(f"[INFO] [launch]: All log files can be found below {log_dir}", flush=True)
    return await supervisor.run()


def run_headless(plan: Plan) -> int:
    return asyncio.run(_run(plan, run_log_dir()))
