"""A plain `--headless` launch pays for what it uses: the inspector's requests and plugins
are not made at start, and still found by anything that reads the registry."""

from __future__ import annotations

import subprocess
import sys

from tuilaunch.engine.launcher import BLACK_BOX_ENV
from tuilaunch.engine.ros.record.recorder import BLACK_BOX_ENV as RECORDER_BLACK_BOX_ENV


def test_the_launcher_reads_the_recorders_black_box_variable() -> None:
    assert BLACK_BOX_ENV == RECORDER_BLACK_BOX_ENV


def test_a_headless_supervisor_loads_no_inspector_until_asked(tmp_path) -> None:
    script = (
        "import sys\n"
        "from pathlib import Path\n"
        "from tuilaunch.engine.launcher import make_supervisor\n"
        "from tuilaunch.engine.plan.model import Plan\n"
        "plan = Plan(file='x.py', arguments=[], processes=[], actions=[], tree=[],\n"
        "            params_dir='')\n"
        f"s = make_supervisor(plan, Path({str(tmp_path)!r}), served=False)\n"
        "loaded = [m for m in ('tuilaunch.engine.ros.inspector',\n"
        "          'tuilaunch.engine.ros.record.recorder',\n"
        "          'tuilaunch.engine.run.vocabulary.ros_requests') if m in sys.modules]\n"
        "print(s.inspector, s.recorder, loaded)\n"
        "from tuilaunch.engine.run.vocabulary.request import REQUESTS, from_message\n"
        "from tuilaunch.engine.run.vocabulary.requests import Topics\n"
        "print(len(REQUESTS) >= 48, from_message({'op': 'topics'}) == Topics())\n"
        f"served = make_supervisor(plan, Path({str(tmp_path)!r}))\n"
        "print(type(served.inspector).__name__, type(served.recorder).__name__)\n")
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         timeout=60, check=True).stdout.splitlines()
    assert out == ["None None []", "True True", "Inspector Recorder"]
