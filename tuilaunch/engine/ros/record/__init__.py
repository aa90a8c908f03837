"""Recording the launch's topics and output into MCAP, where the nodes run.

`definitions.py` (a type's full `ros2msg` text, as rosbag2's MCAP storage writes it, from the
installed interface packages), `tape.py` (what is recorded, in memory: channels and
messages, bounded in seconds and bytes; an output line as an `rcl_interfaces/msg/Log`),
`taker.py` (the topics' serialized messages taken on a thread of their own, never
deserialized), `mcap_out.py` (an MCAP file written from a tape's records), `recorder.py`
(the session requests `record_start`, `record_take`, `record_stop`, `black_box`,
`black_box_write`, and the black box written when a process dies unasked).

Nothing here is imported by a launch without a recording or a black box: the plugin's module
(`recorder.py`) imports neither rclpy nor mcap.
"""
