"""The real-process tests: processes, terminals, rclpy nodes, DDS, sshd, gdb, a browser."""
