"""`SimpleLauncher(use_sim_time='auto')`: is /clock published on the live graph?"""

from __future__ import annotations

import os
import subprocess
import sys
from functools import lru_cache

# A short-lived child process, so that the launcher's own rclpy context (RosBridge) is not
# created while the file is merely being loaded.
_PROBE = """
import sys, time, rclpy
rclpy.init()
node = rclpy.create_node('tuilaunch_clock_probe')
deadline = time.monotonic() + float(sys.argv[1])
found = False
while time.monotonic() < deadline and not found:
    found = node.count_publishers('/clock') > 0
    time.sleep(0.1)
print('yes' if found else 'no')
rclpy.shutdown()
"""


@lru_cache(maxsize=1)
def clock_is_published(wait: float = 2.0) -> bool:
    forced = os.environ.get("TUILAUNCH_SIM_TIME")
    if forced is not None:
        return forced.lower() in ("1", "true", "yes")
    try:
        done = subprocess.run([sys.executable, "-c", _PROBE, str(wait)], capture_output=True,
                              text=True, timeout=wait + 15)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return done.stdout.strip().endswith("yes")
