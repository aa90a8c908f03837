"""The App is composed of objects (issue 45): the keyboard, the inspector, navigation,
quitting and the status line are objects it holds, each over a small host interface, not
mixins sharing `self`; its keys name the object they go to."""

from __future__ import annotations

import inspect

from textual.binding import Binding

from tuilaunch.tui.app import TuiLaunchApp
from tuilaunch.tui.inspect.inspector import Inspector
from tuilaunch.tui.keys.keyboard import NodeKeyboard
from tuilaunch.tui.navigation import Navigation
from tuilaunch.tui.quitting import Quitting


def own_classes(cls: type) -> list[type]:
    return [c for c in cls.__mro__ if c.__module__.startswith("tuilaunch.")]


def test_the_app_is_three_classes_of_fifty_methods_at_most() -> None:
    classes = own_classes(TuiLaunchApp)
    assert len(classes) <= 3, [c.__name__ for c in classes]
    methods = {name for c in classes for name, value in vars(c).items()
               if inspect.isfunction(value)}
    assert len(methods) <= 50, sorted(methods)


def test_the_concerns_are_objects_not_bases() -> None:
    for concern in (NodeKeyboard, Inspector, Navigation, Quitting):
        assert concern not in TuiLaunchApp.__mro__
        assert own_classes(concern) == [concern]  # no App, no widget: a plain object


def test_each_key_names_an_action_the_app_has() -> None:
    """A key's action is the app's, or its object's by name (`keyboard('type_into')`): a
    binding left naming an action that went with a mixin would do nothing."""
    for binding in TuiLaunchApp.BINDINGS:
        assert isinstance(binding, Binding)
        name = binding.action.split("(")[0]
        assert callable(getattr(TuiLaunchApp, f"action_{name}", None)), binding.action
