"""The Nodes tab: the group tree, the detail line above it and the output pane, and how the
engine's events show in them (shared with the fleet view, which shows one tree a session)."""
