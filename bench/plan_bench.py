"""Time and peak memory to load a launch file and resolve its plan, for 10/100/1000 nodes.

Each size runs in its own process so peak memory (ru_maxrss) belongs to that size alone;
the plan (load + resolve) is the best of 3 such processes. Target: a plan of 1000 nodes in
at most 0.1 s. ros2 launch is not installed here (its own figure would be its
`generate_launch_description` and visit of the same file).

    python bench/plan_bench.py
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

SIZES = (10, 100, 1000)


def launch_text(nodes: int) -> str:
    """Nodes spread over robots > arms > groups, with namespaces, conditions and parameters."""
    return textwrap.dedent(f"""
        from simple_launch import SimpleLauncher
        from simple_launch.events import When, OnProcessStart

        def generate_launch_description():
            sl = SimpleLauncher(namespace='fleet')
            sl.declare_arg('rate', 2.0, description='rate')
            sl.declare_arg('extra', True, description='extra nodes')
            made = 0
            robot = 0
            first = None
            while made < {nodes}:
                with sl.group(ns=f'robot{{robot}}'):
                    for arm in range(2):
                        with sl.group(ns=f'arm{{arm}}', if_arg='extra'):
                            with sl.group(unless_condition=sl.py_eval(sl.arg('rate'), ' > 100')):
                                for i in range(5):
                                    if made == {nodes}:
                                        break
                                    node = sl.node('tuilaunch_demos', 'talker', name=f'n{{i}}',
                                                   parameters={{'rate': sl.arg('rate'),
                                                                'message': f'm{{made}}'}},
                                                   remappings={{'chatter': 'out'}})
                                    first = first or node
                                    made += 1
                robot += 1
            with sl.group(when=When(first, OnProcessStart, 1.0)):
                sl.log_info('first node started')
            return sl.launch_description()
    """)


def measure_one(nodes: int) -> dict[str, float]:
    from tuilaunch.engine import load_file, resolve
    from tuilaunch.engine.packages import ensure_environment

    ensure_environment()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"gen_{nodes}.py"
        path.write_text(launch_text(nodes))
        start = time.perf_counter()
        loaded = load_file(str(path))
        loaded_at = time.perf_counter()
        plan = resolve(loaded, {"rate": "5"})
        resolved_at = time.perf_counter()
        again = resolve(loaded, {"rate": "7"})
        again_at = time.perf_counter()
    assert len(plan.enabled_processes()) == nodes == len(again.processes)
    return {"nodes": nodes, "load_s": loaded_at - start, "resolve_s": resolved_at - loaded_at,
            "re_resolve_s": again_at - resolved_at,
            "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def main() -> None:
    if len(sys.argv) == 3 and sys.argv[1] == "--one":
        print(json.dumps(measure_one(int(sys.argv[2]))))
        return
    baseline = json.loads(subprocess.run(
        [sys.executable, __file__, "--one", "1"], capture_output=True, text=True,
        check=True).stdout)
    print(f"{'nodes':>6} {'plan s':>8} {'load s':>8} {'resolve s':>10} {'re-resolve s':>13} "
          f"{'peak RSS MB':>12} {'over 1-node MB':>15}")
    for size in SIZES:
        rows = [json.loads(subprocess.run([sys.executable, __file__, "--one", str(size)],
                                          capture_output=True, text=True, check=True).stdout)
                for _ in range(3)]
        row = min(rows, key=lambda r: r["load_s"] + r["resolve_s"])
        print(f"{row['nodes']:>6} {row['load_s'] + row['resolve_s']:>8.3f} "
              f"{row['load_s']:>8.3f} {row['resolve_s']:>10.3f} "
              f"{row['re_resolve_s']:>13.3f} {row['peak_rss_mb']:>12.1f} "
              f"{row['peak_rss_mb'] - baseline['peak_rss_mb']:>15.1f}")
    print(f"target: a plan (load + resolve) of 1000 nodes in at most 0.1 s; load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
