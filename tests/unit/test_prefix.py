"""Launch prefixes applied as ros2 launch applies them.

Expectations come from ros2/launch `launch/descriptions/executable.py` (`Executable.__init__`:
the filter is only consulted when no own prefix was given; `Executable.prepare`:
`re.match(prefix_filter, os.path.basename(cmd[0]))`, then `shlex.split(prefix) + cmd`), its
tests `test_execute_process_prefix_filter_*` in `launch/test/launch/test_execute_process.py`,
and ros2/launch_ros `ros2launch/command/launch.py` / `ros2launch/api/api.py` for the options.
"""

from __future__ import annotations

import os
import sys

import pytest

from tuilaunch.engine.errors import LaunchError
from tuilaunch.engine.plan.command.prefix import (
    final_cmd,
    prefix_applies,
    prefix_arguments,
    with_prefix,
)

TALKER = ["/opt/ros/jazzy/lib/demo_nodes_cpp/talker", "--ros-args", "-r", "__node:=talker"]


def test_global_prefix_goes_before_every_command_without_a_filter() -> None:
    assert final_cmd(TALKER, None, "gdb -ex run --args") == \
        ["gdb", "-ex", "run", "--args", *TALKER]


def test_no_prefix_anywhere_leaves_the_command_alone() -> None:
    assert final_cmd(TALKER, None) == TALKER


def test_the_filter_is_matched_against_the_executables_basename() -> None:
    # test_execute_process_prefix_filter_match: filter = basename(sys.executable)
    python = [sys.executable, "-c", "print('action')"]
    assert final_cmd(python, None, "time", os.path.basename(sys.executable))[0] == "time"
    # test_execute_process_prefix_filter_no_match
    assert final_cmd(python, None, "time", "no-match") == python


def test_the_filter_is_re_match_anchored_at_the_start_only() -> None:
    assert prefix_applies(TALKER, "talk")  # re.match: a prefix of the name is enough
    assert prefix_applies(TALKER, "talker|listener")
    assert not prefix_applies(TALKER, "alker")  # not re.search: no match in the middle
    assert not prefix_applies(TALKER, "demo_nodes_cpp")  # not the full path
    assert not prefix_applies(TALKER, ".*/talker")
    assert prefix_applies(TALKER, "")  # empty regex matches every string


def test_an_own_prefix_replaces_the_global_one_whatever_the_filter() -> None:
    # test_execute_process_prefix_filter_override_in_launch_file
    assert final_cmd(TALKER, "echo", "time", "no-match") == ["echo", *TALKER]
    assert final_cmd(TALKER, "valgrind --tool=memcheck", "time", "talker") == \
        ["valgrind", "--tool=memcheck", *TALKER]


def test_an_own_empty_prefix_still_turns_the_global_one_off() -> None:
    # `prefix is None` decides in Executable.__init__: '' is a prefix given
    assert final_cmd(TALKER, "", "time") == TALKER


def test_prefix_words_split_as_a_shell_does() -> None:
    assert final_cmd(["node"], None, "xterm -e 'gdb -ex run --args'") == \
        ["xterm", "-e", "gdb -ex run --args", "node"]


def test_bad_prefix_or_filter_is_one_line_naming_it() -> None:
    with pytest.raises(LaunchError, match="launch-prefix-filter '\\[' is not a regular"):
        final_cmd(TALKER, None, "gdb", "[")
    with pytest.raises(LaunchError, match="launch-prefix \"gdb 'x\" cannot be split"):
        final_cmd(TALKER, None, "gdb 'x")


def test_cli_options_become_launch_arguments_appended_last() -> None:
    assert prefix_arguments("gdb -ex run --args", "talker") == \
        ["launch-prefix:=gdb -ex run --args", "launch-prefix-filter:=talker"]
    assert prefix_arguments(None, None) == []
    assert prefix_arguments("", None) == []  # `if args.launch_prefix:` adds nothing
    with pytest.raises(LaunchError, match="--launch-prefix must be given"):
        prefix_arguments(None, "talker")
    with pytest.raises(LaunchError, match="not a regular expression"):
        prefix_arguments("gdb", "(")


def test_an_operator_prefix_must_name_a_program() -> None:
    assert with_prefix(TALKER, "env A=1") == ["env", "A=1", *TALKER]
    with pytest.raises(LaunchError, match="'no-such-debugger' is not a program on PATH"):
        with_prefix(TALKER, "no-such-debugger --args")
    with pytest.raises(LaunchError, match="the prefix is empty"):
        with_prefix(TALKER, "  ")
