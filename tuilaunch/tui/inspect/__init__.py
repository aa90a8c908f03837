"""The TUI's side of the ROS inspector: the Topics, Services and Params tabs' requests and
streams (inspector.py), log levels, recordings and the black box, and plots (the plot
screen opened from a tab, and `tuilaunch plot` full screen)."""
