"""Clients of a session server, for the commands and the TUI."""
