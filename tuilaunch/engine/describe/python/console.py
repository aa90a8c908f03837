"""simple_launch's own messages while a file loads, printed as simple_launch prints them:
`[simple_launch]: message` in its colour (green for information, yellow for warnings), on
stdout, so people who know its lines find them (e.g. which Gazebo world file was found)."""

from __future__ import annotations


def _say(message: str, colour: int) -> None:
    print(f"\033[{colour}m[simple_launch]: {message}\033[0m", flush=True)


def info(message: str) -> None:
    _say(message, 92)


def warn(message: str) -> None:
    _say(message, 93)
