"""The lifecycle transitions an operator may ask of a managed node, by the state it is in:
the TUI offers them (its `]`/`[` steps and palette), the server's lifecycle plugin
(engine/ros/lifecycle.py) performs them."""

from __future__ import annotations

AVAILABLE: dict[str, list[str]] = {
    "unconfigured": ["configure", "unconfigured_shutdown"],
    "inactive": ["activate", "cleanup", "inactive_shutdown"],
    "active": ["deactivate", "active_shutdown"],
}
"""Transitions an operator can ask for, by the state a node is in."""


def available_transitions(state: str | None) -> list[str]:
    """What an operator can ask of a node in this state."""
    return list(AVAILABLE.get(state or "", []))


__all__ = ["AVAILABLE", "available_transitions"]
