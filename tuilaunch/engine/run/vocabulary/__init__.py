"""The words a session server and its clients share, and nothing that runs a launch:
the events (`events.py`), the requests and their replies (`requests.py`, `ros_requests.py`,
`status.py`'s StatusReply, encoded and decoded in `request.py`), the lifecycle transitions
an operator may ask (`lifecycle.py`), a line's text as a screen shows it (`text.py`) and
the node names read in it (`reported_names.py`).

The client and the TUI import these, never the supervisor or the processes' modules (an
import-linter contract in pyproject.toml): an attached TUI loads nothing that runs a launch.
"""
