"""tuilaunch: a terminal UI launcher and inspector for ROS 2."""

__version__ = "0.1.0"
