"""An action that raises when it is performed fails alone: one error line naming it and where
it is written, and the launch goes on and stops as usual (launch's event handlers' entities
are visited one by one; an exception in one is that action's, and SIGINT still ends the
run). Before, the supervisor waited for such an action forever and ignored every signal.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

from ..conftest import run_headless, wait_for

HEADER = """
from launch import LaunchDescription
from launch.actions import (ExecuteProcess, LogInfo, OpaqueFunction, RegisterEventHandler,
                            TimerAction)
from launch.event_handlers import OnProcessExit
from launch.substitutions import LaunchConfiguration
"""


def _run_until_interrupted(path: Path, wanted: tuple[str, ...], marker: str) -> str:
    """Runs the file headless until every `wanted` text was printed, sends SIGINT once; the
    launch must end by itself (a hang fails the wait) with nothing left running."""
    out = run_headless(path, until=wanted)
    wait_for(lambda: not _running(marker), what=f"no {marker} left running")
    return out


def _running(marker: str) -> bool:
    done = subprocess.run(["pgrep", "-f", marker], capture_output=True, text=True)
    return bool(done.stdout.strip())


def test_a_handler_action_that_raises_fails_alone_and_sigint_ends_the_launch(write):
    marker = "sleep 61.5"
    path = write(HEADER + f"""
def handler(event, context):
    return [LogInfo(msg=LaunchConfiguration('never_declared'))]

def generate_launch_description():
    first = ExecuteProcess(cmd=['true'], name='first')
    return LaunchDescription([
        ExecuteProcess(cmd={marker.split()!r}, name='sleeper'),
        first,
        RegisterEventHandler(OnProcessExit(target_action=first, on_exit=handler)),
        TimerAction(period=0.5, actions=[LogInfo(msg='still going')]),
    ])
""")
    out = _run_until_interrupted(path, ("never_declared", "still going"), marker)
    lines = out.splitlines()
    failure = [line for line in lines if "never_declared" in line]
    assert len(failure) == 1, out
    assert failure[0].startswith("[ERROR] [event_callback-1]: event_callback failed: "), out
    assert f"{path}:9" in failure[0], out
    assert "Traceback" not in out, out
    assert "[WARNING] [launch]: user interrupted with ctrl-c (SIGINT)" in lines, out


def test_an_opaque_function_that_raises_at_event_time_names_its_line(write):
    marker = "sleep 62.5"
    path = write(HEADER + f"""
def boom(context):
    raise RuntimeError('boom at event time')

def generate_launch_description():
    first = ExecuteProcess(cmd=['true'], name='first')
    return LaunchDescription([
        ExecuteProcess(cmd={marker.split()!r}, name='sleeper'),
        first,
        RegisterEventHandler(OnProcessExit(target_action=first,
                                           on_exit=[OpaqueFunction(function=boom)])),
    ])
""")
    out = _run_until_interrupted(path, ("boom at event time",), marker)
    failure = [line for line in out.splitlines() if "boom at event time" in line]
    assert len(failure) == 1 and failure[0].startswith("[ERROR] "), out
    assert f"{path}:9" in failure[0], out
    assert "Traceback" not in out, out
    assert "[WARNING] [launch]: user interrupted with ctrl-c (SIGINT)" in out.splitlines(), out
