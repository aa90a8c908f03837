"""Tests that start no process and no ROS graph: plain objects, files, a Textual app in
its pilot at most. Real-process tests are in tests/ (the integration tests)."""
