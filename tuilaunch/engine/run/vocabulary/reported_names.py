"""The node names processes report in their log lines, for nodes the launch file does not name.

A node whose name is chosen by its own code (`Node(package=..., executable=...)` without
`name=`) has no full name in the plan; rcutils' console format carries its logger name
(`[INFO] [1795323834.94] [r1.talker]: ...`), which is the node's namespace and name joined by
dots. The TUI and the session server both map such processes to graph nodes this way, and
both forget a process's names when it starts again (`forget` at its `started` event): a
relaunch, a restart or a respawn may run it under another namespace (robot:=r1 -> r2), and
only the lines of its current run say where it is now.

Not every logger in a node's lines is the node's: at `--log-level debug` its libraries
speak first (`[rcl]: Initializing node ...`, `[rcl.logging_rosout]`, `[rclpy]`,
`[rmw_fastrtps_cpp]`, `[class_loader.impl]`), and a name taken from them (`/rcl`) is no
node on the graph. Those loggers are the ROS client libraries' and middleware's own
(`LIBRARY_LOGGER`), never a node's: they are not read as names.
"""

from __future__ import annotations

import re
from collections.abc import Iterable

from .text import strip_ansi

ROS_LOG_PREFIX = re.compile(
    r"^\[(DEBUG|INFO|WARN|WARNING|ERROR|FATAL)\]\s*(?:\[(\d+(?:\.\d+)?)\]\s*)?"
    r"(?:\[([^\]\s]*)\]:?\s?)?")
"""rcutils' default console format: level, optional stamp, optional logger name."""

LIBRARY_LOGGER = re.compile(
    r"^(rcl|rclpy|rclcpp|rcutils|rmw|rosidl|tracetools|class_loader|pluginlib|ament_index|"
    r"rcpputils|rosbag2|rcl_logging|message_filters|image_transport)(_[A-Za-z0-9_]+)?"
    r"(\.|$)")
"""Loggers of the ROS client libraries, the middleware and the plugin loaders (`rcl`,
`rcl.logging_rosout`, `rclcpp_lifecycle`, `rmw_cyclonedds_cpp`, ...): their lines are in
a node's output, but their names are not the node's."""

MAX_NAMES = 8
"""Names kept per process: a node's sub-loggers add a few; more is a process printing
other processes' lines, which would only mislead."""


def current_node_name(full_name: str | None, reported: Iterable[str]) -> str | None:
    """The one rule for a process's node name in every view: the name the plan gives it,
    else the one its current run reported (the first in order when its sub-loggers add
    more); None until it says."""
    if full_name:
        return full_name
    names = sorted(reported)
    return names[0] if names else None


def node_of_logger(logger: str) -> str:
    """`r1.talker` -> `/r1/talker`."""
    return "/" + logger.replace(".", "/")


class ReportedNames:
    """process id -> the node names its log lines reported (`/ns/name`, a few at most)."""

    def __init__(self) -> None:
        self.names: dict[str, set[str]] = {}

    def add_logger(self, process: str, logger: str) -> bool:
        """Whether `logger` is a node's name (a library's is left out)."""
        if LIBRARY_LOGGER.match(logger):
            return False
        names = self.names.setdefault(process, set())
        if len(names) < MAX_NAMES:
            names.add(node_of_logger(logger))
        return True

    def add_lines(self, process: str, lines: Iterable[str]) -> None:
        for raw in lines:
            match = ROS_LOG_PREFIX.match(strip_ansi(raw))
            if match and match.group(3):
                self.add_logger(process, match.group(3))

    def forget(self, process: str) -> None:
        """The process starts again: the names of its previous run no longer hold."""
        names = self.names.get(process)
        if names:
            names.clear()  # in place: views hold this dict and its sets

    def get(self, process: str) -> set[str]:
        return self.names.get(process, set())
