"""The inspector's commands: `topics`, `hz`, `echo`, `params`, `log-level` (inspector.py)
and `plot` (plot.py)."""
