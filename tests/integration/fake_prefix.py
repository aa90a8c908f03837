"""A test ament prefix of FAKE packages standing in for what cannot be installed here.

Gazebo (`gz`, ros_gz_sim, ros_gz_bridge, ros_gz_image) and tf2_ros are not on PyPI: each fake
executable is a probe that records its argv, the parameters of its `--params-file`s and, for
a bridge, the YAML its `config_file` parameter names, as JSON in $PROBE_DIR, then exits.
"""

from __future__ import annotations

import json
import os
import sys
import textwrap
from pathlib import Path
from typing import Any

from .launch_world import make_package

PROBE = f"""#!{sys.executable}
# FAKE executable for tests: records how it was started, then exits
import json, os, sys, time
import yaml

params = {{}}
argv = sys.argv[1:]
for i, word in enumerate(argv):
    if word == "--params-file":
        with open(argv[i + 1]) as handle:
            for values in yaml.safe_load(handle).values():
                params.update(values.get("ros__parameters", {{}}))
record = {{"exe": os.path.basename(sys.argv[0]), "argv": argv, "params": params}}
config = params.get("config_file")
if config:
    # the real parameter_bridge reads its config once, at start
    record["config"] = open(config).read() if os.path.exists(config) else None
out = os.path.join(os.environ["PROBE_DIR"], f"{{record['exe']}}-{{os.getpid()}}.json")
with open(out, "w") as handle:
    json.dump(record, handle)
"""

# Our own stand-in for ros_gz_sim's gz_sim.launch.py, in its style: arguments declared, then
# an opaque function reads them and runs `gz sim ARGS --force-version V` through a shell.
GZ_SIM_LAUNCH = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, OpaqueFunction
from launch.substitutions import LaunchConfiguration


def start_gazebo(context, *args, **kwargs):
    gz_args = LaunchConfiguration('gz_args').perform(context)
    version = LaunchConfiguration('gz_version').perform(context)
    return [ExecuteProcess(cmd=['gz sim', gz_args, '--force-version', version], shell=True,
                           output='screen')]


def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('gz_args', default_value='', description='gz sim arguments'),
        DeclareLaunchArgument('gz_version', default_value='8', description='Gazebo version'),
        OpaqueFunction(function=start_gazebo),
    ])
"""

PACKAGES: dict[str, list[str]] = {
    "ros_gz_sim": ["create"],
    "ros_gz_bridge": ["parameter_bridge"],
    "ros_gz_image": ["image_bridge"],
    "tf2_ros": ["static_transform_publisher"],
    "simple_launch": ["generate_gz_world"],
}


def make_prefix(root: Path, packages: dict[str, list[str]] | None = None,
                share_files: dict[str, str] | None = None) -> Path:
    """An ament prefix under root: packages with probe executables, `bin/gz`, share files."""
    prefix = root / "fake_prefix"
    for package, executables in (packages or PACKAGES).items():
        make_package(prefix, package, executables, probe=PROBE)
    if "ros_gz_sim" in (packages or PACKAGES):
        launch = prefix / "share" / "ros_gz_sim" / "launch"
        launch.mkdir(parents=True, exist_ok=True)
        (launch / "gz_sim.launch.py").write_text(GZ_SIM_LAUNCH)
    _script(prefix / "bin" / "gz", PROBE)
    for relative, text in (share_files or {}).items():
        target = prefix / "share" / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(textwrap.dedent(text))
    return prefix


def _script(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    path.chmod(0o755)


def prefix_env(prefix: Path, probe_dir: Path) -> dict[str, str]:
    """Environment for a tuilaunch run that sees the fake prefix first."""
    probe_dir.mkdir(parents=True, exist_ok=True)
    return {
        "AMENT_PREFIX_PATH": os.pathsep.join(
            [str(prefix), *filter(None, os.environ.get("AMENT_PREFIX_PATH", "").split(":"))]),
        "PATH": f"{prefix / 'bin'}{os.pathsep}{os.environ.get('PATH', '')}",
        "PROBE_DIR": str(probe_dir),
    }


def probe_records(probe_dir: Path) -> list[dict[str, Any]]:
    return [json.loads(p.read_text()) for p in sorted(probe_dir.glob("*.json"))]
