"""The ROS layer's two errors, apart from the code that raises them: the plugins every
launch loads (actions, inspector) catch them without importing the bridge, the message
helpers and their dataclasses, which a launch of plain processes never uses."""

from __future__ import annotations

from ..errors import LaunchError


class RosError(Exception):
    """A ROS operation that did not succeed: timed out, service gone, refused."""


class MessageError(LaunchError):
    """A request dict that does not fit its message type."""
