"""Plots without ROS running: numeric fields of message types by dotted path, the
decimation into buckets that keep a one-sample spike, and what a client's plot shows of
the points it was sent (rebinned to its width, its last, min and max)."""

from __future__ import annotations

import math

import pytest
from geometry_msgs.msg import PolygonStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState, LaserScan
from std_msgs.msg import Bool, String

from tuilaunch.client.inspect.plot_series import PlotSeries, Source, rebinned
from tuilaunch.engine.ros.plot.buckets import FieldBuckets
from tuilaunch.engine.ros.plot.fields import (
    FieldError,
    compile_path,
    has_sequences,
    numeric_fields,
    stamp_reader,
)


def test_numeric_fields_are_listed_by_dotted_path_nested_and_indexed():
    odometry = numeric_fields(Odometry)
    assert odometry[:3] == ["header.stamp.sec", "header.stamp.nanosec", "pose.pose.position.x"]
    assert "pose.pose.orientation.w" in odometry and "twist.twist.angular.z" in odometry
    # a fixed-size array lists each element; strings (frame ids) are not numbers
    assert [f for f in odometry if f.startswith("pose.covariance")] == \
        [f"pose.covariance[{i}]" for i in range(36)]
    assert not any("frame_id" in f for f in odometry)
    # a sequence lists its first element; a sequence of messages their numeric fields
    assert numeric_fields(LaserScan)[-2:] == ["ranges[0]", "intensities[0]"]
    assert "polygon.points[0].y" in numeric_fields(PolygonStamped)
    assert numeric_fields(Bool) == ["data"] and numeric_fields(String) == []


def test_a_path_reads_its_value_from_a_message():
    odometry = Odometry()
    odometry.pose.pose.position.x = 3.25
    odometry.twist.covariance[35] = -1.5
    assert compile_path(Odometry, "pose.pose.position.x").value(odometry) == 3.25
    assert compile_path(Odometry, "twist.covariance[35]").value(odometry) == -1.5
    scan = LaserScan(ranges=[1.0, 2.0, 4.5])
    assert compile_path(LaserScan, "ranges[2]").value(scan) == 4.5
    # any index of a sequence is accepted; a message too short has no value there
    assert compile_path(LaserScan, "ranges[7]").value(scan) is None
    assert compile_path(Bool, "data").value(Bool(data=True)) == 1.0


@pytest.mark.parametrize("path", ["nope", "ranges", "header.frame_id", "ranges[0].x",
                                  "angle_min[0]", "", "a..b", "header.stamp"])
def test_a_path_that_is_no_number_names_the_topic_and_its_numeric_fields(path):
    with pytest.raises(FieldError) as error:
        compile_path(LaserScan, path, "/scan")
    text = str(error.value)
    assert "\n" not in text
    assert text.startswith(f"/scan (sensor_msgs/msg/LaserScan) has no numeric field {path!r}")
    assert text.endswith("its numeric fields: header.stamp.sec, header.stamp.nanosec, "
                         "angle_min, angle_max, angle_increment, time_increment, scan_time, "
                         "range_min, range_max, ranges[0], intensities[0]")


def test_a_long_list_of_fields_is_cut_in_an_error():
    with pytest.raises(FieldError, match=r", \.\.\. \(\d+ more\)$"):
        compile_path(Odometry, "pose.covariance[36]", "/odom")


def test_buckets_keep_min_max_and_last_so_a_one_sample_spike_survives():
    buckets = FieldBuckets(width=0.05)
    rate = 1000
    for k in range(10 * rate):  # 10 s of a 1 kHz sine, one sample of 10 at k = 4321
        value = 10.0 if k == 4321 else 2 * math.sin(2 * math.pi * 0.5 * k / rate)
        buckets.add(k / rate, value)
    buckets.close_until(10.0 + 0.05)
    sent = buckets.since(-1)
    # at most 20 buckets a second whatever the rate, every sample in one of them
    assert len(sent) <= 10 * 20 + 1
    assert sum(b.count for b in sent) == 10 * rate
    assert max(b.high for b in sent) == 10.0
    spike = next(b for b in sent if b.high == 10.0)
    assert spike.low < 10.0 and spike.count > 1  # folded with its neighbours, still there
    assert min(b.low for b in sent) == pytest.approx(-2.0, rel=1e-3)
    assert sent[-1].last == pytest.approx(2 * math.sin(2 * math.pi * 0.5 * 9999 / rate))
    # what was sent is not sent again
    assert buckets.since(sent[-1].index) == []


def test_a_slow_topic_bucket_closes_when_its_time_is_over():
    buckets = FieldBuckets(width=0.05)
    buckets.add(100.01, 1.0)
    buckets.close_until(100.02)
    assert buckets.since(-1) == []  # still open
    buckets.close_until(100.06)
    assert [b.point(100) for b in buckets.since(-1)] == [[10, 1.0, 1.0, 1.0]]


def test_the_plot_keeps_its_own_stream_points_once_and_rebins_them_keeping_the_spike():
    old = Source("", "/a", ["x"])
    series = PlotSeries([old])
    source = Source("", "/a", ["x"])
    assert series.put(source) is old  # the same topic asked again: its new stream
    points = [[t * 50, -1.0, 1.0 if t != 50 else 9.0, 0.5] for t in range(200)]  # ms
    assert not series.add({"tag": old.tag, "t0": 7, "points": {"x": points}})  # replaced
    assert series.add({"tag": source.tag, "t0": 7, "points": {"x": points[:100]}})
    assert series.add({"tag": source.tag, "t0": 7, "points": {"x": points[90:]}})  # once
    assert len(series.points["/a/x"]) == 200
    end = series.newest()
    assert end == pytest.approx(7 + 199 / 20)
    stats = series.stats("/a/x", 10.0, end)
    assert (stats.last, stats.low, stats.high) == (0.5, -1.0, 9.0)
    xs, ys = rebinned(series.shown("/a/x", 10.0, end), end - 10.0, end, 40)
    assert len(xs) == len(ys) <= 80 and max(ys) == 9.0 and min(ys) == -1.0
    assert xs == sorted(xs)


def test_a_sample_message_lists_every_element_of_its_sequences():
    joints = JointState(name=["a", "b", "c"], position=[0.1, 0.2, 0.3], velocity=[1.0])
    fields = numeric_fields(JointState, sample=joints)
    assert [f for f in fields if "[" in f] == [
        "position[0]", "position[1]", "position[2]", "velocity[0]", "effort[0]"]
    assert has_sequences(JointState) and not has_sequences(Odometry)
    # without a message, the type alone: a sequence's first element
    assert "position[1]" not in numeric_fields(JointState)


def test_a_stamp_is_read_where_the_type_has_a_header():
    joints = JointState()
    joints.header.stamp.sec, joints.header.stamp.nanosec = 1_000_000, 250_000_000
    read = stamp_reader(JointState)
    assert read is not None and read(joints) == 1_000_000.25
    assert stamp_reader(Bool) is None


def test_a_stamp_older_than_what_was_sent_is_folded_at_the_end_not_lost():
    buckets = FieldBuckets(width=0.05)
    for k in range(10):
        buckets.add(100 + k * 0.05, float(k))
    buckets.add(99.0, -5.0)  # a stamp from the past: into the open bucket
    buckets.close_until(200)
    sent = buckets.since(-1)
    assert sum(b.count for b in sent) == 11 and min(b.low for b in sent) == -5.0
    assert [b.time for b in sent] == sorted(b.time for b in sent)
