"""The live ROS graph: the rclpy bridge, messages as dicts, the sim clock."""
