"""A small ROS world for launch-API tests: an ament prefix of fake packages whose
executables record their argv and parameter files, and an extension package written in the
style of nav2_common (a Substitution that rewrites a YAML file, one that replaces strings,
a multi-robot argument parser reading sys.argv).

Real robots' packages (nav2, turtlebot3, ros2_control) are C++ and not installable here; the
probes stand in for their executables and record what ros2 launch would have handed them.
"""

from __future__ import annotations

import json
import os
import stat
import sys
import textwrap
from pathlib import Path

PROBE = """\
#!{python}
# a test double for a C++ node: records argv, parameters files, env, then behaves per env
import json, os, sys, time
import yaml
out = os.environ.get("PROBE_DIR")
files = [a for i, a in enumerate(sys.argv) if i and sys.argv[i - 1] == "--params-file"]
params = {{}}
for f in files:
    try:
        with open(f) as h:
            params[f] = yaml.safe_load(h)
    except OSError as exc:
        params[f] = str(exc)
name = os.path.basename(sys.argv[0])
if out:
    with open(os.path.join(out, f"{{name}}-{{os.getpid()}}.json"), "w") as h:
        json.dump({{"exe": name, "argv": sys.argv[1:], "params": params,
                   "env": {{k: v for k, v in os.environ.items() if k.startswith("PROBE_")}}}}, h)
print(f"{{name}} up", flush=True)
time.sleep(float(os.environ.get("PROBE_SECONDS_" + name.upper(),
                                os.environ.get("PROBE_SECONDS", "0"))))
sys.exit(int(os.environ.get("PROBE_EXIT_" + name.upper(), "0")))
"""

EXTENSION = '''\
"""An extension in the style of nav2_common.launch, written for these tests."""
import sys
import tempfile

import launch
import yaml
from launch.utilities import normalize_to_list_of_substitutions, perform_substitutions


class RewrittenParams(launch.Substitution):
    """Reads a params YAML, replaces leaf values by key, optionally nests it under a key."""

    def __init__(self, source_file: launch.SomeSubstitutionsType, param_rewrites,
                 root_key=None, convert_types=False):
        super().__init__()
        self._source = normalize_to_list_of_substitutions(source_file)
        self._rewrites = {k: normalize_to_list_of_substitutions(v)
                          for k, v in param_rewrites.items()}
        self._root = normalize_to_list_of_substitutions(root_key) if root_key else None
        self._convert = convert_types

    def describe(self):
        return "RewrittenParams"

    def perform(self, context: launch.LaunchContext):
        path = launch.utilities.perform_substitutions(context, self._source)
        with open(path) as handle:
            data = yaml.safe_load(handle)
        values = {k: perform_substitutions(context, v) for k, v in self._rewrites.items()}
        self._rewrite(data, values)
        if self._root is not None:
            root = context.perform_substitution(self._root[0]) if len(self._root) == 1 \\
                else perform_substitutions(context, self._root)
            if root:
                data = {root: data}
        out = tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False)
        yaml.dump(data, out)
        out.close()
        return out.name

    def _rewrite(self, data, values):
        for key, value in list(data.items()):
            if isinstance(value, dict):
                self._rewrite(value, values)
            elif key in values:
                text = values[key]
                if self._convert and text.replace(".", "", 1).isdigit():
                    text = float(text) if "." in text else int(text)
                elif text.lower() in ("true", "false"):
                    text = text.lower() == "true"
                data[key] = text


class ReplaceText(launch.Substitution):
    """Copies a file with strings replaced, only when its condition holds."""

    def __init__(self, source_file, replacements, condition=None):
        super().__init__()
        self._source = normalize_to_list_of_substitutions(source_file)
        self._replacements = replacements
        self._condition = condition

    def perform(self, context):
        path = perform_substitutions(context, self._source)
        if self._condition is not None and not self._condition.evaluate(context):
            return path
        with open(path) as handle:
            text = handle.read()
        for old, new in self._replacements.items():
            text = text.replace(old, perform_substitutions(context, new))
        out = tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False)
        out.write(text)
        out.close()
        return out.name


class RobotPoses:
    """Reads robots:=name={x: 1.0, y: 2.0};name2={...} from the ros2 launch command line."""

    def __init__(self, argument):
        self.argument = argument

    def value(self):
        for arg in sys.argv[4:]:
            if arg.startswith(self.argument + ":="):
                robots = {}
                for item in arg.split(":=", 1)[1].split(";"):
                    if "=" in item:
                        name, pose = item.split("=", 1)
                        robots[name.strip()] = yaml.safe_load(pose)
                return robots
        return {}


class Broken(launch.Substitution):
    def perform(self, context):
        return {}["missing key"]


class EchoAction(launch.Action):
    """A third-party action: execute() returns more actions."""

    def __init__(self, text, **kwargs):
        super().__init__(**kwargs)
        self.text = text

    def execute(self, context):
        from launch.actions import LogInfo
        value = perform_substitutions(context, normalize_to_list_of_substitutions(self.text))
        return [LogInfo(msg="echo " + value)]
'''


def make_package(prefix: Path, package: str, executables: list[str] = (),
                 files: dict[str, str] | None = None, probe: str | None = None) -> Path:
    """An ament package in `prefix`: index marker, package.xml, probe executables (this
    module's PROBE unless another script is given), share files."""
    index = prefix / "share" / "ament_index" / "resource_index" / "packages"
    index.mkdir(parents=True, exist_ok=True)
    (index / package).write_text("")
    share = prefix / "share" / package
    share.mkdir(parents=True, exist_ok=True)
    (share / "package.xml").write_text(f"<package><name>{package}</name></package>\n")
    lib = prefix / "lib" / package
    lib.mkdir(parents=True, exist_ok=True)
    for exe in executables:
        path = lib / exe
        path.write_text(probe if probe is not None else PROBE.format(python=sys.executable))
        path.chmod(path.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    for relative, text in (files or {}).items():
        target = share / relative
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(textwrap.dedent(text))
    return share


def install_extension(root: Path, name: str = "fake_nav_common") -> Path:
    """The nav2_common-style extension as an importable package under `root`."""
    package = root / name / "launch"
    package.mkdir(parents=True, exist_ok=True)
    (root / name / "__init__.py").write_text("")
    (package / "__init__.py").write_text(
        "from .extension import Broken, EchoAction, ReplaceText, RewrittenParams, RobotPoses\n")
    (package / "extension.py").write_text(EXTENSION)
    return root


def probe_records(probe_dir: Path) -> list[dict]:
    return [json.loads(p.read_text()) for p in sorted(probe_dir.glob("*.json"))]


def world_env(prefix: Path, ext_root: Path, probe_dir: Path) -> dict[str, str]:
    return {
        "AMENT_PREFIX_PATH": os.pathsep.join([str(prefix), os.environ.get(
            "AMENT_PREFIX_PATH", "")]),
        "PYTHONPATH": os.pathsep.join([str(ext_root), os.environ.get("PYTHONPATH", "")]),
        "PROBE_DIR": str(probe_dir),
    }
