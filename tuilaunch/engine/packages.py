"""Packages through the ament index: a sourced /opt/ros, a colcon workspace, or a virtualenv.

A virtualenv holding the ROS wheels is itself an ament prefix; it is added to the search
path so users need not export AMENT_PREFIX_PATH themselves.
"""

from __future__ import annotations

import os
import sys
from functools import lru_cache
from pathlib import Path

from .errors import Origin, PackageError

_MARKER = Path("share") / "ament_index" / "resource_index" / "packages"


def _is_prefix(path: Path) -> bool:
    return (path / _MARKER).is_dir()


def environment_prefixes() -> list[Path]:
    """AMENT_PREFIX_PATH, then the running interpreter's prefix if it is an ament prefix."""
    return list(_prefixes(os.environ.get("AMENT_PREFIX_PATH", "")))


@lru_cache(maxsize=4)
def _prefixes(variable: str) -> tuple[Path, ...]:
    # cached on the variable's value: a plan asks once per node, and 1000 nodes must plan fast
    prefixes = [Path(p) for p in variable.split(os.pathsep) if p]
    own = Path(sys.prefix)
    if _is_prefix(own) and own not in prefixes:
        prefixes.append(own)
    return tuple(prefixes)


ENVIRONMENT_CHANGES: dict[str, dict[str, str]] = {}
"""What `ensure_environment` changed in tuilaunch's environment, and so in every child's
(ros2 launch changes nothing): name -> {"before", "after", "why"}; `--print --json` shows it."""


def ensure_environment() -> None:
    """Make AMENT_PREFIX_PATH name the interpreter's prefix, for us and for every child."""
    prefixes = environment_prefixes()
    joined = os.pathsep.join(str(p) for p in prefixes)
    if joined and os.environ.get("AMENT_PREFIX_PATH") != joined:
        _changed("AMENT_PREFIX_PATH", joined, "the packages installed in tuilaunch's own "
                 "environment are found as a sourced workspace's would be")
        _package_prefix_map.cache_clear()
    bin_dir = str(Path(sys.executable).parent)
    # Scripts installed in a virtualenv prefix start with `/usr/bin/env python3`: that must
    # find this interpreter even when the venv was not activated, as sourcing would do.
    if _is_prefix(Path(sys.prefix)) and bin_dir not in os.environ.get("PATH", "").split(":"):
        _changed("PATH", bin_dir + os.pathsep + os.environ.get("PATH", ""),
                 "scripts installed in tuilaunch's virtual environment start with "
                 "`/usr/bin/env python3`: they must find its interpreter, as sourcing would")


def _changed(name: str, value: str, why: str) -> None:
    before = ENVIRONMENT_CHANGES.get(name, {}).get("before", os.environ.get(name, ""))
    os.environ[name] = value
    ENVIRONMENT_CHANGES[name] = {"before": before, "after": value, "why": why}


@lru_cache(maxsize=4)
def _package_prefix_map(search_path: str) -> dict[str, Path]:
    found: dict[str, Path] = {}
    for prefix in [Path(p) for p in search_path.split(os.pathsep) if p]:
        marker = prefix / _MARKER
        try:
            names = os.listdir(marker)
        except OSError:
            continue
        for name in names:
            found.setdefault(name, prefix)
    return found


def known_packages() -> dict[str, Path]:
    return _package_prefix_map(_search_path(os.environ.get("AMENT_PREFIX_PATH", "")))


@lru_cache(maxsize=4)
def _search_path(variable: str) -> str:
    return os.pathsep.join(str(p) for p in _prefixes(variable))


def package_prefix(package: str, origin: Origin | None = None) -> Path:
    prefix = known_packages().get(package)
    if prefix is None:
        searched = ", ".join(str(p) for p in environment_prefixes()) or "(nothing)"
        raise PackageError(
            f"package '{package}' not found in the ament index (searched {searched})",
            origin,
            hint="source the workspace that provides it, or install it into this environment",
        )
    return prefix


def package_share(package: str, origin: Origin | None = None) -> Path:
    return package_prefix(package, origin) / "share" / package


def find_executable(package: str, executable: str, origin: Origin | None = None) -> Path:
    """`<prefix>/lib/<package>/<executable>`, as ros2 run finds it."""
    # plain strings, not Path arithmetic: this runs once per node of the plan
    candidate = os.path.join(package_prefix(package, origin), "lib", package, executable)
    if os.path.isfile(candidate) and os.access(candidate, os.X_OK):
        return Path(candidate)
    lib = package_prefix(package, origin) / "lib" / package
    available = sorted(p.name for p in lib.iterdir() if os.access(p, os.X_OK)) if lib.is_dir()\
        else []
    choices = f"available: {', '.join(available)}" if available \
        else f"the package installs no executables in {lib}"
    raise PackageError(f"executable '{executable}' not found in package '{package}' ({choices})",
                       origin)


def find_in_share(package: str, file_name: str, origin: Origin | None = None) -> Path:
    """A file anywhere below the package share (simple_launch's `find` without file_dir)."""
    share = package_share(package, origin)
    direct = share / file_name
    if direct.is_file():
        return direct
    for root, _dirs, files in os.walk(share):
        if file_name in files:
            return Path(root) / file_name
    raise PackageError(
        f"file '{file_name}' not found in the share of package '{package}' ({share})", origin
    )


def find_launch_file_in_share(package: str, file_name: str) -> Path:
    """`ros2 launch PACKAGE FILE`: the one file of that name below the package's share.

    As ros2 launch does, a name found in two places is an error naming both, not a guess."""
    share = package_share(package)
    found = sorted(Path(root) / file_name for root, _dirs, files in os.walk(share)
                   if file_name in files)
    if not found:
        raise PackageError(f"launch file '{file_name}' not found in package '{package}' ({share})")
    if len(found) > 1:
        raise PackageError(
            f"launch file '{file_name}' is in package '{package}' more than once: "
            + ", ".join(str(p) for p in found),
            hint="give the path of the one to launch")
    return found[0]
