"""`os.environ` as launch-time code sees it.

In launch, `context.environment` *is* the launch process's `os.environ`: the environment
actions change it in the order they are visited, and every piece of Python that runs later
(an OpaqueFunction, an included file's module code, PythonExpression, a condition) reads
the change. The engine keeps each scope's changes as an overlay (name -> value, None for
unset) on the environment tuilaunch started with, shows that overlay in `os.environ` while a
plan is made, and puts the launcher's own environment back afterwards, so a relaunch starts
from where tuilaunch started, as a fresh `ros2 launch` would.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from contextlib import contextmanager

Overlay = dict[str, "str | None"]


def set_environ(target: Mapping[str, str]) -> None:
    """Makes os.environ equal `target`, touching only the names that differ."""
    for name in [name for name in os.environ if name not in target]:
        del os.environ[name]
    for name, value in target.items():
        if os.environ.get(name) != value:
            os.environ[name] = value


def with_overlay(base: Mapping[str, str], overlay: Mapping[str, str | None]) -> dict[str, str]:
    environ = dict(base)
    for name, value in overlay.items():
        if value is None:
            environ.pop(name, None)
        else:
            environ[name] = value
    return environ


def changes(before: Mapping[str, str], after: Mapping[str, str]) -> Overlay:
    """What turned `before` into `after`, as an overlay."""
    found: Overlay = {name: value for name, value in after.items()
                      if before.get(name) != value}
    found.update({name: None for name in before if name not in after})
    return found


@contextmanager
def captured_environ() -> Iterator[Overlay]:
    """Runs user code that may write os.environ (`os.environ['X'] = ...` in a launch file):
    what it changed is handed back as an overlay (launch keeps such writes for what follows
    and for the processes it starts) and os.environ is put back as it was."""
    before = dict(os.environ)
    found: Overlay = {}
    try:
        yield found
    finally:
        found.update(changes(before, os.environ))
        set_environ(before)


class EnvironView:
    """Keeps os.environ showing one scope's overlay while a plan is made; `restore` puts
    back what it was at the start."""

    def __init__(self) -> None:
        self.base: dict[str, str] = dict(os.environ)
        self._shown: Overlay = {}

    def show(self, overlay: Mapping[str, str | None]) -> None:
        if overlay != self._shown:
            set_environ(with_overlay(self.base, overlay))
            self._shown = dict(overlay)

    def restore(self) -> None:
        set_environ(self.base)
        self._shown = {}


@contextmanager
def shown_environ(overlay: Mapping[str, str | None]) -> Iterator[None]:
    """os.environ shows `overlay` while launch-time code runs when an event happens (a
    LogInfo's message, a handler's callback), and is put back afterwards."""
    view = EnvironView()
    view.show(overlay)
    try:
        yield
    finally:
        view.restore()
