"""The recording's parts that need no process: a type's full definition as rosbag2 writes
it, an output line as rcl_interfaces/msg/Log in CDR, and the tape's bounds."""

from __future__ import annotations

from mcap_ros2._dynamic import generate_dynamic

from tuilaunch.engine.ros.record.definitions import DELIMITER, full_definition
from tuilaunch.engine.ros.record.recorder import LOG_FALLBACK
from tuilaunch.engine.ros.record.tape import OVERHEAD, Tape, line_message


def test_a_definition_has_its_dependencies_once_after_the_delimiter():
    text = full_definition("sensor_msgs/msg/Image")
    assert text.startswith("# This message contains an uncompressed image")
    assert [line for line in text.splitlines() if line.startswith("MSG: ")] == \
        ["MSG: std_msgs/Header", "MSG: builtin_interfaces/Time"]
    assert text.count(DELIMITER + "\nMSG: ") == 2
    assert full_definition("no_such_pkg/msg/Thing") == ""


def test_an_output_line_reads_back_as_a_log_message():
    for definition in (full_definition("rcl_interfaces/msg/Log"), LOG_FALLBACK):
        decode = generate_dynamic("rcl_interfaces/msg/Log", definition)["rcl_interfaces/msg/Log"]
        line = "\x1b[33m[WARN] [1700000000.5] [talker]: hot in here: é\x1b[0m"
        log = decode(line_message(1_700_000_000_123_456_789, "talker-1", line, "stderr"))
        assert (log.stamp.sec, log.stamp.nanosec) == (1_700_000_000, 123_456_789)
        assert (log.level, log.name) == (30, "talker-1")
        assert log.msg == "[WARN] [1700000000.5] [talker]: hot in here: é"
        plain = decode(line_message(0, "p", "Traceback (most recent call last):", "stderr"))
        assert plain.level == 30
        assert decode(line_message(0, "p", "hello", "stdout")).level == 20


def test_a_tape_drops_the_oldest_past_its_bytes_or_its_seconds():
    tape = Tape(max_bytes=10 * (1000 + OVERHEAD), seconds=2.0)
    for k in range(30):
        tape.add("/image", k * 100_000_000, bytes(1000))  # 10 a second
    assert len(tape.records) == 10 and tape.size <= tape.max_bytes
    assert tape.records[0][1] == 20 * 100_000_000  # the newest ten
    tape.max_bytes = 1 << 30
    for k in range(30, 60):
        tape.add("/small", k * 100_000_000, b"x")
    _, kept = tape.snapshot(59 * 100_000_000)
    assert kept[0][1] == 39 * 100_000_000  # the last 2 s
    taken, dropped = tape.take(1 << 20)
    assert len(taken) == 21 and dropped == 39 and not tape.records
