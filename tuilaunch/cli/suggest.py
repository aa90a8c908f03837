"""What a mistyped launch command line is told: `did you mean` for a file and a package, the
launch files of a package given without one, a `name=value` missing its colon, a file that
is no launch file; `guess` serves the session commands too (a mistyped process)."""

from __future__ import annotations

import os
import re
from pathlib import Path

from ..engine.errors import LaunchError, PackageError
from ..engine.packages import known_packages, package_share

LAUNCH_SUFFIXES = tuple(f"{sep}launch.{ext}" for sep in "._"
                        for ext in ("py", "xml", "yaml", "yml"))
"""A launch file in a package's share, as ros2 launch lists them."""
LAUNCH_EXTENSIONS = (".py", ".xml", ".yaml", ".yml", ".launch")
_ASSIGNMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_.-]*)=(.*)$", re.S)


def check_assignments(positional: list[str]) -> None:
    """`robot=r2`: a launch argument missing its colon, not a package or a file name."""
    for word in positional:
        match = _ASSIGNMENT.match(word)
        if match and not os.path.exists(word):
            raise LaunchError(f"{word!r} is not a launch argument: ros2 launch arguments "
                              "are written with ':='",
                              hint=f"{match.group(1)}:={match.group(2)}")


def close_matches(word: str, choices: list[str]) -> list[str]:
    import difflib  # paid by a mistyped name alone: every launch imports this module

    return difflib.get_close_matches(word, choices, n=3, cutoff=0.6)


def did_you_mean(word: str, choices: list[str]) -> str:
    close = close_matches(word, choices)
    return said_as_guess(close)


def said_as_guess(close: list[str]) -> str:
    return f"did you mean {' or '.join(repr(c) for c in close)}?" if close else ""


def launch_files(package: str) -> list[str]:
    found: set[str] = set()
    for _root, _dirs, files in os.walk(package_share(package)):
        found.update(f for f in files if f.endswith(LAUNCH_SUFFIXES))
    return sorted(found)


def command_guess(word: str) -> str:
    """`tuilaunch list`, `tuilaunch atach nuc:base`: a session command mistyped reads as a
    launch file's or a package's name; the command it resembles, if any."""
    from .parsers import COMMANDS

    close = close_matches(word, list(COMMANDS))
    return f"did you mean the command {close[0]!r}? (tuilaunch {close[0]} ...)" if close else ""


def missing_file(path: str) -> PackageError:
    """A FILE that does not exist: a package of that name lists its launch files, else the
    names in its folder that resemble it."""
    if path in known_packages():
        files = launch_files(path)
        listed = ", ".join(files) if files else "none in its share"
        return PackageError(f"{path} is a package: give one of its launch files too "
                            f"({listed})", hint=f"tuilaunch {path} FILE")
    # suggested only from the folder the path names (this one for a bare file name), and
    # only files a launch could be; a bare word without an extension names a package to a
    # ros2 launch user: the files around them are no guess for it
    folder = Path(path).parent
    names = []
    if "/" in path or path.endswith(LAUNCH_EXTENSIONS):
        try:
            names = [e.name for e in os.scandir(folder)
                     if e.name.endswith(LAUNCH_EXTENSIONS) and e.is_file()]
        except OSError:
            pass
    guess = did_you_mean(Path(path).name, names)
    if not guess and "/" not in path:
        guess = did_you_mean(path, list(known_packages()))
        guess = guess.replace("did you mean", "did you mean the package") if guess else ""
        if not guess and not path.endswith(LAUNCH_EXTENSIONS):
            guess = command_guess(path)
    hint = guess or "give a path, or PACKAGE FILE to search a package's share"
    return PackageError(f"launch file {path} does not exist", hint=hint)


def missing_package(package: str) -> PackageError | None:
    """A PACKAGE not in the ament index, with the names it resembles; None when it is."""
    packages = known_packages()
    if package in packages:
        return None
    guess = did_you_mean(package, list(packages)) or command_guess(package)
    return PackageError(f"package '{package}' not found in the ament index",
                        hint=guess or "source the workspace that provides it, or install it "
                        "into this environment")


def missing_in_package(package: str, name: str, error: PackageError) -> PackageError:
    """A FILE not in a PACKAGE's share: the launch files it has."""
    if "not found in package" not in str(error):
        return error
    files = launch_files(package)
    guess = did_you_mean(name, files)
    listed = f"its launch files: {', '.join(files)}" if files else \
        "its share has no launch file"
    return PackageError(f"launch file '{name}' not found in package '{package}'",
                        hint=f"{guess} ({listed})" if guess else listed)


def not_a_launch_file(path: str, error: LaunchError) -> LaunchError:
    """A file the loader could not read whose name says it is no launch file."""
    if path.endswith(LAUNCH_EXTENSIONS):
        return error
    return LaunchError(f"{path} is not a launch file: ros2 launch files are Python (.py), "
                       "XML (.launch.xml) or YAML (.launch.yaml)",
                       hint=f"as Python, it reads: {error}")
