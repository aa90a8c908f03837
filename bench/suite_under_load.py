"""The test suite on a busy machine: runs `pytest -q` N times in a row while CPU burners keep
every core busy, and prints each run's result line and duration.

CI runs on a developer's machine that is rarely idle; a test that only passes on a quiet one
blocks landings. This is how the suite is shown to hold:

    python bench/suite_under_load.py --runs 3 --burners 2 [-- extra pytest arguments]

The burners are plain `while True: pass` processes at normal priority (as a build or another
test run would be); they are killed however this script ends.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--burners", type=int, default=os.cpu_count() or 2)
    parser.add_argument("pytest_args", nargs="*")
    options = parser.parse_args()
    # Started in the background (`cmd &` without job control), this script ignores SIGINT and
    # so would every test process: the tests of Ctrl+C would see nothing happen. A handled
    # signal is reset to the default in a child, an ignored one is not.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGQUIT, signal.SIG_DFL)
    burners = [subprocess.Popen([sys.executable, "-c", "while True: pass"],
                                start_new_session=True) for _ in range(options.burners)]
    results: list[tuple[int, float, str]] = []
    try:
        for run in range(1, options.runs + 1):
            began = time.monotonic()
            done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                                   *options.pytest_args], cwd=ROOT, capture_output=True,
                                  text=True)
            took = time.monotonic() - began
            last = [line for line in done.stdout.splitlines() if line.strip()][-1:] or ["?"]
            results.append((done.returncode, took, last[0]))
            print(f"run {run}: exit {done.returncode} in {took / 60:.1f} min: {last[0]}",
                  flush=True)
            if done.returncode != 0:
                # the whole report kept: the tail names the failures, not always why
                kept = Path(tempfile.gettempdir()) / f"suite-under-load-run{run}.log"
                kept.write_text(done.stdout + done.stderr)
                print(done.stdout[-5000:])
                print(f"(the whole report: {kept})")
                break
    finally:
        for burner in burners:
            os.killpg(burner.pid, signal.SIGKILL)
            burner.wait()
    print(f"\n{options.burners} CPU burners on {os.cpu_count()} cores; "
          f"{sum(1 for r in results if r[0] == 0)}/{options.runs} runs passed")
    return 0 if len(results) == options.runs and all(r[0] == 0 for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
