"""What a plot of several fields is shaped into, without a session: the command line's words
into topics of sessions, the columns' names, the panels of readable scales, XY pairs, the
CSV of every message merged across streams, and the CSV the plot screen's `S` saves."""

from __future__ import annotations

import csv
import io

import pytest

from tuilaunch.client.inspect.plot_series import PlotSeries, Source
from tuilaunch.client.inspect.plot_shapes import (
    RowMerge,
    command_words,
    panels,
    series_csv,
    xy_pairs,
)
from tuilaunch.engine.run.session.session_dir import SessionError


def test_a_word_starting_with_a_slash_starts_a_topic_and_host_name_another_session():
    asked = command_words("sim", "/cmd", ["x", "/joints", "position[0]", "position[1]",
                                          "robot2:base", "/odom", "pose.pose.position.x",
                                          "/cmd", "y"])
    assert [(a.session, a.topic, a.fields) for a in asked] == [
        ("sim", "/cmd", ["x"]),
        ("sim", "/joints", ["position[0]", "position[1]"]),
        ("robot2:base", "/odom", ["pose.pose.position.x"]),
        ("robot2:base", "/cmd", ["y"]),
    ]
    # a topic named twice in one session is one stream, its fields together
    twice = command_words("sim", "/cmd", ["x", "/joints", "position[0]", "/cmd", "y"])
    assert [(a.topic, a.fields) for a in twice] == [("/cmd", ["x", "y"]),
                                                     ("/joints", ["position[0]"])]


@pytest.mark.parametrize("words, said", [
    (["x", "/joints"], "/joints has no field to plot"),
    (["/joints", "x"], "/cmd has no field to plot"),
    (["x", "robot2:base"], "robot2:base is followed by no topic"),
    (["x", "robot2:base", "y"], "robot2:base is followed by 'y', not a topic"),
])
def test_words_that_make_no_plot_are_one_line_naming_the_word(words, said):
    with pytest.raises(SessionError) as error:
        command_words("sim", "/cmd", words)
    assert str(error.value).startswith(said)
    assert "\n" not in str(error.value)


def test_columns_are_topic_slash_field_with_the_session_once_there_are_several():
    series = PlotSeries([Source("sim", "/cmd", ["x"]), Source("sim", "/joints",
                                                                ["position[2]"])])
    assert series.columns == ["/cmd/x", "/joints/position[2]"]
    series.add({"tag": series.sources[0].tag, "t0": 10, "points": {"x": [[0, 1, 1, 1]]}})
    series.put(Source("robot2:base", "/cmd", ["x"]))
    assert series.columns == ["sim:/cmd/x", "sim:/joints/position[2]", "robot2:base:/cmd/x"]
    assert list(series.points["sim:/cmd/x"]) == [(10.0, 1.0, 1.0, 1.0)]  # kept, renamed


def test_fields_of_magnitudes_ten_times_apart_get_panels_of_their_own():
    assert panels({"a": (-1.0, 1.0), "b": (-2.0, 3.0)}) == [["a", "b"]]
    assert panels({"small": (-1.0, 1.0), "big": (-1e5, 1e5), "also": (0.0, 5.0),
                   "huge": (0.0, 1.5e5)}) == [["small", "also"], ["big", "huge"]]
    # a constant field reads on any axis
    assert panels({"a": (5.0, 5.0), "b": (-1e5, 1e5)}) == [["a", "b"]]
    # 1 +- 0.5 beside 1e5 +- 1: each flat on the other's axis
    assert len(panels({"a": (0.5, 1.5), "b": (1e5 - 1, 1e5 + 1)})) == 2


def test_xy_pairs_each_y_with_the_x_at_or_before_its_time():
    xs = [(1.0, 0, 0, 10.0), (2.0, 0, 0, 20.0), (3.0, 0, 0, 30.0)]
    ys = [(0.5, 0, 0, -1.0), (1.0, 0, 0, 1.0), (2.5, 0, 0, 2.0), (3.0, 0, 0, 3.0)]
    assert xy_pairs(xs, ys) == ([10.0, 20.0, 30.0], [1.0, 2.0, 3.0])


def rows_of(lines: list[str]) -> list[list[str]]:
    return [line.rstrip("\n").split(",") for line in lines]


def test_csv_rows_of_several_streams_come_in_time_order_one_message_a_row():
    merge = RowMerge([2, 1], relative=True)
    merge.add(0, [[100.0, 1.0, 2], [100.2, 3.0, 4]], now=0.0)
    assert merge.lines(now=0.1) == []  # the other stream may still send an earlier row
    merge.add(1, [[100.1, 0.5], [100.3, 7.0]], now=0.1)
    assert rows_of(merge.lines(now=0.1)) == [
        ["0.000000", "1.0", "2", ""],
        ["0.100000", "", "", "0.5"],
        ["0.200000", "3.0", "4", ""],
    ]
    # a stream gone quiet holds nothing for longer than HOLD_S
    assert rows_of(merge.lines(now=0.2 + RowMerge.HOLD_S)) == [["0.300000", "", "", "7.0"]]
    stamped = RowMerge([1], relative=False)
    stamped.add(0, [[1000000.25, None]], now=0.0)
    assert stamped.lines(now=0.0, final=True) == ["1000000.250000,\n"]


def test_s_saves_every_point_held_with_its_min_and_max_a_row_per_point():
    one, two = Source("", "/a", ["x", "y"]), Source("", "/b", ["v"])
    series = PlotSeries([one, two])
    series.add({"tag": one.tag, "t0": 1000,
                "points": {"x": [[0, -1.0, 1.0, 0.5], [50, 0.0, 2.0, 2.0]],
                           "y": [[0, 1e5, 2e5, 1.5e5], [50, 1e5, 1e5, 1e5]]}})
    series.add({"tag": two.tag, "t0": 1000, "points": {"v": [[25, 7.0, 7.0, 7.0]]}})
    text, count = series_csv(series)
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0] == ["time", "/a/x", "/a/x min", "/a/x max", "/a/y", "/a/y min",
                       "/a/y max", "/b/v", "/b/v min", "/b/v max"]
    assert count == 3 and rows[1:] == [
        ["1000.000000", "0.5", "-1.0", "1.0", "150000.0", "100000.0", "200000.0", "", "", ""],
        ["1000.025000", "", "", "", "", "", "", "7.0", "7.0", "7.0"],
        ["1000.050000", "2.0", "0.0", "2.0", "100000.0", "100000.0", "100000.0", "", "", ""],
    ]
