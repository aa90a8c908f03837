"""What a client keeps of the inspector's streams: the streams asked for (watches.py), the
ROS graph calls as session requests (session_graph.py), a plot's points and shapes, and a
recording's side."""
