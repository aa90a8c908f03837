"""The demo nodes a `component_container` can load, by plugin name `tuilaunch_demos::Name`."""

from .lifecycle_talker import LifecycleTalker
from .listener import Listener
from .talker import Talker

__all__ = ["LifecycleTalker", "Listener", "Talker"]
