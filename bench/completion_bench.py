"""How long a Tab press takes: the whole `tuilaunch` process argcomplete runs, for the local
completions side by side (commands, packages, a package's launch files, folders, a launch
file's arguments and their choices), with `python -c pass` as the floor; and which heavy
modules the completion path loads (none may be rclpy or textual).

    python bench/completion_bench.py
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROUNDS = 7
EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
LINES = {
    "commands (tuilaunch lo)": "tuilaunch lo",
    "packages (tuilaunch std_)": "tuilaunch std_",
    "launch files (tuilaunch tuilaunch_demos )": "tuilaunch tuilaunch_demos ",
    "folders (tuilaunch examples/)": f"tuilaunch {EXAMPLES}/",
    "arguments (tuilaunch bringup.py )": f"tuilaunch {EXAMPLES}/bringup.py ",
    "choices (tuilaunch bringup.py mode:=)": f"tuilaunch {EXAMPLES}/bringup.py mode:=",
    "sessions (tuilaunch status )": "tuilaunch status ",
}


def one(line: str, out: str, extra: list[str] | None = None) -> tuple[float, str]:
    env = {**os.environ, "_ARGCOMPLETE": "1", "_ARGCOMPLETE_SHELL": "bash", "COMP_LINE": line,
           "COMP_POINT": str(len(line)), "_ARGCOMPLETE_STDOUT_FILENAME": out}
    started = time.perf_counter()
    done = subprocess.run([sys.executable, *(extra or []), "-m", "tuilaunch"], env=env,
                          capture_output=True, text=True)
    return time.perf_counter() - started, done.stderr


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        out = str(Path(folder) / "answer")
        floor = statistics.median(
            (lambda s: (subprocess.run([sys.executable, "-c", "pass"]),
                        time.perf_counter() - s)[1])(time.perf_counter())
            for _ in range(ROUNDS))
        print(f"{'python -c pass (the floor)':45} {floor * 1000:7.1f} ms")
        for label, line in LINES.items():
            times = [one(line, out)[0] for _ in range(ROUNDS)]
            answer = Path(out).read_text().replace("\x0b", " ")[:40]
            print(f"{label:45} {statistics.median(times) * 1000:7.1f} ms   {answer}")
        _, imports = one("tuilaunch lo", out, ["-X", "importtime"])
        heavy = sorted({row.split("|")[-1].strip().split(".")[0] for row in
                        imports.splitlines() if row.startswith("import time:")}
                       & {"rclpy", "textual", "rich", "yaml", "lark"})
        print(f"heavy modules loaded completing 'tuilaunch lo': {heavy or 'none'}")


if __name__ == "__main__":
    main()
