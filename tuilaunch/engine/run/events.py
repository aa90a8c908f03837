"""The engine's events, as the engine's modules import them: defined in
vocabulary/events.py, with the other words a session server and its clients share."""

from __future__ import annotations

from .vocabulary.events import *  # noqa: F403
from .vocabulary.events import __all__ as __all__
