"""A running node's logger levels, through its logger service.

rclpy and rclcpp nodes offer `<node>/set_logger_levels` and `<node>/get_logger_levels`
(rcl_interfaces) only when created with `enable_logger_service=True`. Without them the level
can only be given at start (`--ros-args --log-level`): the error says so, and the caller
offers that restart.
"""

from __future__ import annotations

import asyncio

from .calls import BridgeCalls, RosError

LEVELS = {"unset": 0, "debug": 10, "info": 20, "warn": 30, "error": 40, "fatal": 50}
LEVEL_NAMES = {number: name for name, number in LEVELS.items()}


class NoLoggerService(RosError):
    """The node has no logger service: its level can only be set by restarting it."""


def level_number(level: str | int) -> int:
    if isinstance(level, int):
        if level in LEVEL_NAMES:
            return level
    elif level.strip().lower() in LEVELS:
        return LEVELS[level.strip().lower()]
    elif level.strip().lower() == "warning":
        return LEVELS["warn"]
    raise RosError(f"'{level}' is not a logger level (one of {', '.join(LEVELS)})")


def logger_name(node: str) -> str:
    """rcl's logger name of a node: `/ns/talker` logs as `ns.talker`."""
    return node.strip("/").replace("/", ".")


async def has_logger_service(bridge: BridgeCalls, node: str, wait: float = 2.0) -> bool:
    """Whether the node offers its logger service. A node's services are discovered a
    little after the node itself: a node just started gets `wait` seconds to show it."""
    wanted = f"{node}/set_logger_levels"
    loop = asyncio.get_running_loop()
    deadline = loop.time() + wait
    while True:
        if any(name == wanted for name, _ in await bridge.list_services()):
            return True
        if loop.time() > deadline:
            break
        await asyncio.sleep(0.1)
    if node not in await bridge.list_nodes():
        raise RosError(f"no node {node} on the ROS graph")
    return False


async def _require_service(bridge: BridgeCalls, node: str) -> None:
    if not await has_logger_service(bridge, node):
        raise NoLoggerService(
            f"{node} has no logger service (the node was not created with "
            f"enable_logger_service=True): restart it with --log-level to change its level")


async def set_level(bridge: BridgeCalls, node: str, level: str | int,
                    logger: str | None = None, timeout: float = 5.0) -> None:
    """Sets the node's logger (or `logger`) to `level` (a name like `debug`, or a number)."""
    from rcl_interfaces.msg import LoggerLevel
    from rcl_interfaces.srv import SetLoggerLevels

    number = level_number(level)
    await _require_service(bridge, node)
    request = SetLoggerLevels.Request(
        levels=[LoggerLevel(name=logger or logger_name(node), level=number)])
    response = await bridge.call_typed(f"{node}/set_logger_levels", SetLoggerLevels,
                                       request, timeout)
    for result in response.results:
        if not result.successful:
            raise RosError(f"{node} refused logger level {LEVEL_NAMES[number]}: "
                           f"{result.reason or 'no reason given'}")


async def get_levels(bridge: BridgeCalls, node: str, loggers: list[str] | None = None,
                     timeout: float = 5.0) -> dict[str, str]:
    """`{logger name: level name}` for the node's own logger (or the given loggers)."""
    from rcl_interfaces.srv import GetLoggerLevels

    await _require_service(bridge, node)
    names = loggers or [logger_name(node)]
    response = await bridge.call_typed(f"{node}/get_logger_levels", GetLoggerLevels,
                                       GetLoggerLevels.Request(names=names), timeout)
    return {entry.name: LEVEL_NAMES.get(entry.level, str(entry.level))
            for entry in response.levels}
