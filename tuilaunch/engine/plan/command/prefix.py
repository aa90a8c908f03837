"""Launch prefixes (gdb, valgrind, `xterm -e`, perf...) as ros2 launch applies them.

The rules, from ros2/launch `launch/descriptions/executable.py` (`Executable.__init__` and
`Executable.prepare`) and ros2/launch_ros `ros2launch` (`command/launch.py`, `api/api.py`):

- A process's own `prefix` (Node / ExecuteProcess `prefix=`, XML `launch-prefix`), when
  given at all, is used alone: the `launch-prefix` launch configuration and its filter are
  ignored, even when the own prefix is empty. The two never combine.
- Without one, the `launch-prefix` launch configuration (default empty) is the prefix, and
  it is applied only when the `launch-prefix-filter` configuration (default empty, which
  matches everything) `re.match`es the basename of the command's first word (the executable
  before any prefix): anchored at the start, not at the end.
- The prefix text is split as a shell would (`shlex.split`) and put before the command.
- `ros2 launch --launch-prefix P --launch-prefix-filter F` become the launch arguments
  `launch-prefix:=P` and `launch-prefix-filter:=F`, appended after the user's own (so they
  win over a `launch-prefix:=` on the command line); an empty option adds nothing; a filter
  without a prefix is refused.

Pure functions: no process is started, nothing is looked up but PATH.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil

from ...errors import LaunchError

LAUNCH_PREFIX = "launch-prefix"
LAUNCH_PREFIX_FILTER = "launch-prefix-filter"


def split_prefix(text: str, what: str = LAUNCH_PREFIX) -> list[str]:
    """The words of a prefix, split as a shell does; one line naming `what` when it cannot."""
    if not text or text.isspace():  # no prefix, the common case: shlex costs per node
        return []
    try:
        return shlex.split(text)
    except ValueError as exc:  # an unclosed quote
        raise LaunchError(f"{what} {text!r} cannot be split into words: {exc}") from None


def prefix_applies(cmd: list[str], prefix_filter: str) -> bool:
    """Whether the global launch-prefix goes before `cmd`: launch's
    `re.match(filter, os.path.basename(cmd[0]))`; an empty filter matches every command."""
    if not cmd:
        return False
    try:
        return re.match(prefix_filter, os.path.basename(cmd[0])) is not None
    except re.error as exc:
        raise LaunchError(f"{LAUNCH_PREFIX_FILTER} {prefix_filter!r} is not a regular "
                          f"expression: {exc}") from None


def final_cmd(cmd: list[str], own_prefix: str | None, launch_prefix: str = "",
              prefix_filter: str = "") -> list[str]:
    """The argv a process is started with, given its command (without any prefix), its own
    prefix (None when the file gave none) and the launch-prefix / launch-prefix-filter
    launch configurations (empty when unset)."""
    if own_prefix is not None:
        return split_prefix(own_prefix, "prefix") + cmd
    if prefix_applies(cmd, prefix_filter):
        return split_prefix(launch_prefix) + cmd
    return list(cmd)


def prefix_arguments(launch_prefix: str | None, prefix_filter: str | None) -> list[str]:
    """The launch arguments `--launch-prefix` / `--launch-prefix-filter` become, to append
    after the user's `name:=value` arguments (later duplicates win, as in ros2 launch)."""
    if launch_prefix is None and prefix_filter is not None:
        raise LaunchError("--launch-prefix must be given when --launch-prefix-filter is")
    arguments = []
    if launch_prefix:
        split_prefix(launch_prefix, "--launch-prefix")  # fails here, not at the first start
        arguments.append(f"{LAUNCH_PREFIX}:={launch_prefix}")
    if prefix_filter:
        prefix_applies(["-"], prefix_filter)  # a bad regex fails here, once
        arguments.append(f"{LAUNCH_PREFIX_FILTER}:={prefix_filter}")
    return arguments


def with_prefix(cmd: list[str], prefix: str, path: str | None = None) -> list[str]:
    """`cmd` started under an operator's tool (`gdb -q -ex run --args`), put before the
    command as it would run; the tool must be a program on `path` (PATH by default), so a
    typo fails with one line instead of a node that dies at once."""
    words = split_prefix(prefix, "prefix")
    if not words:
        raise LaunchError("the prefix is empty: give the tool to run the node under, "
                          "e.g. 'gdb -q -ex run --args'")
    if shutil.which(words[0], path=path) is None:
        raise LaunchError(f"prefix {prefix!r}: {words[0]!r} is not a program on PATH")
    return words + cmd
