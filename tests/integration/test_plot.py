"""Plots of topic fields on a real session of real rclpy publishers of a known signal
(tests/integration/nodes/signal_node.py: a 0.5 Hz sine of amplitude 2, a one-sample spike of
10 every
4 s, the sample's number in z): `tuilaunch plot --csv` prints what was published, the
points a client is sent are bounded and keep the spike, a second client sees the same
points, the plot screen shows the curve and its figures (at 80x24, in the TUI's Topics tab
and full screen in tmux).

One session serves the module: starting one costs seconds of DDS discovery.
"""

from __future__ import annotations

import csv
import io
import itertools
import os
import shutil
import signal
import subprocess
import sys
import textwrap
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from tuilaunch.cli.inspect.inspector import streamed
from tuilaunch.client.link import Link, open_link
from tuilaunch.engine.run.vocabulary.requests import (
    PlotStart,
    Subscribe,
    WatchRates,
    WatchResources,
)

from ..conftest import run_cli, session_folders
from .launch_world import make_package
from .nodes.signal_node import expected
from .session_steps import start_here, stop_here
from .test_sessions import wait_state

SIGNAL_NODE = Path(__file__).resolve().parent / "nodes" / "signal_node.py"
WRAPPER = f"""#!{sys.executable}
import runpy
runpy.run_path({str(SIGNAL_NODE)!r}, run_name="__main__")
"""
LAUNCH = """
from launch import LaunchDescription
from launch_ros.actions import Node


def generate_launch_description():
    return LaunchDescription([
        Node(package='plot_nodes', executable='signal_node', name='wave',
             arguments=['wave', '--topic', '/plot/wave', '--rate', '50']),
        Node(package='plot_nodes', executable='signal_node', name='fast',
             arguments=['fast', '--topic', '/plot/fast', '--rate', '1000']),
    ])
"""
WAVE, FAST = "/plot/wave", "/plot/fast"
X, Z = f"{WAVE}/x", f"{WAVE}/z"


def tl(*args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return run_cli(*args, timeout=timeout)


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    root = tmp_path_factory.mktemp("plot")
    prefix = root / "prefix"
    make_package(prefix, "plot_nodes", ["signal_node"], probe=WRAPPER)
    (root / "plot.launch.py").write_text(textwrap.dedent(LAUNCH))
    with session_folders(root / "log", prefix):
        # the module's setting, started and ended from this process: the commands tested
        # are the ones the tests run on it
        name = start_here(root / "plot.launch.py", "--name", "plt")
        try:
            for process in ("wave-1", "fast-2"):
                wait_state(name, process, "running")
            yield name
        finally:
            stop_here(name)


def csv_rows(text: str) -> tuple[list[str], list[dict[str, str]]]:
    reader = csv.DictReader(io.StringIO(text))
    rows = list(reader)
    return list(reader.fieldnames or []), rows


def test_csv_prints_every_message_as_published(session):
    done = tl("plot", session, WAVE, "x", "y", "z", "--csv", "--duration", "3")
    assert done.returncode == 0, done.stderr
    header, rows = csv_rows(done.stdout)
    assert header == ["time", f"{WAVE}/x", f"{WAVE}/y", f"{WAVE}/z"]
    assert len(rows) > 20
    samples = [int(float(row[f"{WAVE}/z"])) for row in rows]
    # every message, none missing between the first and the last, each value exact
    assert samples == list(range(samples[0], samples[0] + len(samples)))
    for row, k in zip(rows, samples, strict=True):
        assert (float(row[f"{WAVE}/x"]), float(row[f"{WAVE}/y"])) == expected(k, 50.0, 4.0)
    times = [float(row["time"]) for row in rows]
    assert times[0] == 0.0 and times == sorted(times) and times[-1] > 0


def test_csv_of_a_1khz_topic_misses_no_message(session):
    done = tl("plot", session, FAST, "x", "z", "--csv", "--duration", "3")
    assert done.returncode == 0, done.stderr
    _, rows = csv_rows(done.stdout)
    samples = [int(float(row[f"{FAST}/z"])) for row in rows]
    assert len(samples) > 500
    assert samples == list(range(samples[0], samples[0] + len(samples)))
    assert all(float(row[f"{FAST}/x"]) == expected(k, 1000.0, 4.0)[0]
               for row, k in zip(rows, samples, strict=True))


def test_ctrl_c_ends_the_csv_quietly(session):
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", "plot", session, WAVE, "x",
                             "--csv"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline() == f"time,{WAVE}/x\n"
        first = proc.stdout.readline()
        assert first.startswith("0.000000,")
        proc.send_signal(signal.SIGINT)
        rest, errors = proc.communicate(timeout=60)
    finally:
        proc.kill()
        proc.wait()
    assert proc.returncode == 0, errors
    assert errors == ""
    assert all(line.count(",") == 1 for line in rest.splitlines())


@pytest.mark.parametrize("args, words", [
    ((WAVE, "x", "w"), ["/plot/wave (geometry_msgs/msg/Point) has no numeric field 'w'",
                        "its numeric fields: x, y, z"]),
    ((WAVE, "x[0]"), ["has no numeric field 'x[0]'", "x, y, z"]),
    (("/plot/nothing", "x"), ["no topic /plot/nothing on the ROS graph"]),
])
def test_a_field_or_topic_that_is_not_there_is_one_line(session, args, words):
    done = tl("plot", session, *args, "--csv", "--duration", "1")
    assert done.returncode != 0
    assert done.stdout == ""
    assert "Traceback" not in done.stderr
    line, = done.stderr.strip().splitlines()
    assert line.startswith("tuilaunch plot: error: ")
    for word in words:
        assert word in line


def test_an_unknown_session_is_one_line(session):
    done = tl("plot", "no-such-session", WAVE, "x", "--csv")
    assert done.returncode != 0
    assert "no running session named no-such-session" in done.stderr.splitlines()[0]


Points = dict[str, list[list[float]]]


def collect(name: str, topic: str, fields: list[str], seconds: float,
            started: threading.Event | None = None,
            enough: Callable[[Points], bool] | None = None) -> Points:
    """The points a client plotting `fields` is sent over `seconds`, or until they are
    `enough` (then `seconds` only guards against a hang)."""
    points: Points = {f: [] for f in fields}
    link = open_link(name, timeout=60)
    try:
        link.request(Subscribe(max_lines=1, kinds=["plot"]))
        link.request(PlotStart(topic=topic, fields=fields, tag="t"))
        if started is not None:
            started.set()
        for data in streamed(link, "plot", time.monotonic() + seconds):
            assert data["tag"] == "t"
            for field, sent in data["points"].items():
                points[field] += [[data["t0"] + ms / 1000, *rest] for ms, *rest in sent]
            if enough is not None and enough(points):
                break
    finally:
        link.close()
    return points


def first_sent(link: Link, kind: str, count: int) -> list[dict[str, Any]]:
    """The data of the first `count` `kind` events the session sends (one a second); the
    deadline only guards against a hang."""
    return list(itertools.islice(streamed(link, kind, time.monotonic() + 60), count))


def spans_a_spike(points: Points) -> bool:
    """Over 4.5 s of points, with the spike among them (every 4000 samples: every 4 s at
    1 kHz, later on a machine too busy to publish at that rate)."""
    xs = points["x"]
    return bool(xs) and xs[-1][0] - xs[0][0] > 4.5 and max(p[2] for p in xs) == 10.0


def test_a_1khz_plot_is_sent_a_bounded_number_of_points_that_keep_the_spike(session):
    points = collect(session, FAST, ["x", "z"], 60.0, enough=spans_a_spike)
    xs, zs = points["x"], points["z"]
    span = xs[-1][0] - xs[0][0]
    assert span > 4.5
    # at most 20 buckets a second, whatever the rate; z (the sample's number) says how many
    # messages they fold: hundreds a second
    assert len(xs) <= 20 * span + 2
    assert zs[-1][3] - zs[0][3] > 100 * span
    assert max(p[2] for p in xs) == 10.0  # the one-sample spike (every 4 s) survives
    assert min(p[1] for p in xs) == pytest.approx(-2.0, rel=0.01)
    for t, low, high, last in zs:
        assert low <= last <= high and t > 0


def test_a_second_client_sees_the_same_points(session):
    first: dict[str, Any] = {}
    started = threading.Event()

    def first_client() -> None:
        first.update(collect(session, WAVE, ["x"], 8.0, started))

    thread = threading.Thread(target=first_client)
    thread.start()
    try:
        assert started.wait(60)
        time.sleep(2.0)  # the first plots alone for a while: the second is sent that too
        second = collect(session, WAVE, ["x"], 4.0)
    finally:
        thread.join(90)
    a = {round(p[0], 3): p for p in first["x"]}
    b = {round(p[0], 3): p for p in second["x"]}
    common = sorted(set(a) & set(b))
    assert len(common) > 50
    assert all(a[t][1:] == b[t][1:] for t in common)  # min, max, last
    assert min(b) <= min(a) + 0.1  # the points from before the second client came


def test_a_client_that_starts_watching_a_rate_is_sent_the_minutes_before(session):
    watcher = open_link(session, timeout=60)
    try:
        watcher.request(Subscribe(max_lines=1, kinds=["rates"]))
        watcher.request(WatchRates(topics=[WAVE]))
        rates = [data[WAVE]["rate_hz"] for data in first_sent(watcher, "rates", 3)]
        assert len(rates) >= 3
        later = open_link(session, timeout=60)
        try:
            later.request(Subscribe(max_lines=1, kinds=["rates"]))
            history = later.request(WatchRates(topics=[WAVE]))["history"][WAVE]
        finally:
            later.close()
    finally:
        watcher.close()
    # a rate a second while the first client watched: the figures it was sent, in order
    assert any(history[i:i + len(rates)] == rates
               for i in range(len(history) - len(rates) + 1)), (history, rates)
    assert 40 < history[-1] < 60


def test_a_client_that_draws_a_node_trend_is_sent_the_minutes_before(session):
    watcher = open_link(session, timeout=60)
    try:
        watcher.request(Subscribe(max_lines=1, kinds=["trend"]))
        watcher.request(WatchResources(on=True, processes=["wave-1"], trend=["wave-1"]))
        samples = [data["wave-1"] for data in first_sent(watcher, "trend", 3)]
        assert len(samples) >= 3
        assert all(cpu is not None and rss > 10 << 20 for cpu, rss in samples)
        later = open_link(session, timeout=60)
        try:
            later.request(Subscribe(max_lines=1, kinds=["trend"]))
            kept = later.request(WatchResources(on=True, processes=["fast-2"],
                                                trend=["wave-1", "fast-2"]))["history"]
        finally:
            later.close()
    finally:
        watcher.close()
    # a sample a second while the first client watched, each as it was sent to it
    assert set(kept) == {"wave-1", "fast-2"}
    history = kept["wave-1"]
    assert any(history[i:i + len(samples)] == samples
               for i in range(len(history) - len(samples) + 1)), (history, samples)


async def test_the_selected_node_detail_line_draws_its_cpu_and_memory_trend(session):
    from rich.console import Console

    from tuilaunch.tui.app import make_app

    from .test_sessions import status
    from .test_tui import until

    info = status(session)
    app = make_app(info["file"], {}, Path(info["log_dir"]), session_name=session)

    def line() -> str:
        console = Console(width=app.detail_bar.size.width, file=io.StringIO(),
                          color_system=None)
        console.print(app.detail_bar.content)
        return console.file.getvalue()  # type: ignore[attr-defined]

    async with app.run_test(size=(140, 30)) as pilot:
        await until(pilot, lambda: "wave-1" in app.launch_tree.rows)
        while app.nodes.selected_process() != "wave-1":
            await pilot.press("down")
        await until(pilot, lambda: len(app.inspector.trends.get("wave-1", ())) >= 3)
        await until(pilot, lambda: " cpu " in line() and " mem " in line())
        drawn = line()
        assert drawn.startswith("wave-1 (/wave): running")
        cpu, memory = drawn.rstrip().rsplit(" cpu ", 1)[1].split(" mem ")
        for shown in (cpu, memory):  # a bar a column, from the last minutes, then its max
            bars = shown.split()[0]
            assert len(bars) == 10 and set(bars) <= set("▁▂▃▄▅▆▇█"), drawn
            assert "█" in bars  # from zero to the max: the max is a full bar
        assert cpu.split()[1].endswith("%") and memory.split()[1][-1] in "KMG", drawn
        await pilot.press("down")  # another node: its own trend, its minutes before too
        await until(pilot, lambda: line().startswith("fast-2 (/fast)") and " cpu " in line())
        assert len(app.inspector.trends["fast-2"]) >= 3


# --- on screen -------------------------------------------------------------------------------

async def test_p_in_the_topics_tab_plots_the_topic_with_its_figures(session):
    from textual.widgets import DataTable
    from textual_plotext import PlotextPlot

    from tuilaunch.tui.app import make_app
    from tuilaunch.tui.screens.plot_screen import PlotScreen
    from tuilaunch.tui.screens.topics_panel import TopicsPanel

    from .test_sessions import status
    from .test_tui import tab_panel, until

    info = status(session)
    app = make_app(info["file"], {}, Path(info["log_dir"]), session_name=session)
    async with app.run_test(size=(80, 24)) as pilot:
        panel = await tab_panel(pilot, app, "5", TopicsPanel)
        await until(pilot, lambda: WAVE in panel.shown)
        table = panel.query_one(DataTable)
        table.move_cursor(row=panel.shown.index(WAVE))
        await until(pilot, lambda: panel.selected == WAVE)
        # the selected topic's rate over the last minutes, as a sparkline above its detail
        await until(pilot, lambda: len(panel.trend_data) >= 3)
        assert panel.query_one("#tpc-trend").has_class("shown")
        assert 40 < panel.trend_data[-1] < 60
        # a steady 50 Hz is a steady row of high bars, from zero to the max said beside
        bars = str(panel.query_one("#tpc-spark").render()).strip()
        assert len(bars) >= 3 and set(bars) <= set("▇█"), bars
        assert "(0 to " in str(panel.query_one("#tpc-trend-label").render())
        await pilot.press("p")
        await until(pilot, lambda: isinstance(app.screen, PlotScreen))
        screen = app.screen
        assert isinstance(screen, PlotScreen)
        assert screen.series.columns == [X]  # the first numeric field, named TOPIC/FIELD
        # a second field picked: z, the sample's number, says which message was last
        screen.set_fields(["x", "z"])
        await pilot.press("w")  # 60 s: the spike, every 4 s, is on it

        # a trough's lowest samples can be lost on a busy machine (a burst past the
        # subscription's depth), so wait for a trough received whole: 30 a minute
        def settled() -> bool:
            drawn = screen.drawn
            return Z in drawn and X in drawn and drawn[X][2] == 10.0 and \
                drawn[X][1] <= -1.98
        await until(pilot, settled, limit=90)
        last, low, high = screen.drawn[X]
        assert low == pytest.approx(-2.0, rel=0.01) and high == pytest.approx(10.0, rel=0.01)
        k = int(screen.drawn[Z][0])
        assert last == pytest.approx(expected(k, 50.0, 4.0)[0], rel=0.01, abs=1e-3)
        # the curve is drawn (braille dots), with each field's figures beside it; back on
        # the 10 s window (w: 5 min, then 10 s again) it spans the plot's width
        await pilot.press("w", "w")
        assert screen.window == 10.0

        def dots() -> int:
            canvas = screen.query_one(PlotextPlot).render().plain  # type: ignore[union-attr]
            return sum(1 for c in canvas if 0x2800 < ord(c) <= 0x28FF)
        await until(pilot, lambda: dots() > 40, limit=90)
        side = str(screen.query_one("#plot-side").render())
        assert "max  10" in side and f"■ {X}" in side and f"■ {Z}" in side
        await pilot.press("q")
        await until(pilot, lambda: not isinstance(app.screen, PlotScreen))


def tmux(*args: str) -> str:
    return subprocess.run(["tmux", "-L", SOCKET, *args], capture_output=True, text=True,
                          check=False).stdout


SOCKET = f"tuilaunch-plot-{uuid.uuid4().hex[:8]}"


@pytest.mark.skipif(shutil.which("tmux") is None, reason="tmux is not installed")
def test_plot_command_shows_the_curve_full_screen_at_80x24_and_q_leaves(session, tmp_path):
    status_file = tmp_path / "status"
    command = (f"{sys.executable} -m tuilaunch plot {session} {WAVE} x y; "
               f"echo $? > {status_file}")
    env = {**os.environ}
    tmux_env = [f"{k}={env[k]}" for k in ("XDG_RUNTIME_DIR", "ROS_DOMAIN_ID",
                                          "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOG_DIR",
                                          "AMENT_PREFIX_PATH", "PATH") if k in env]
    tmux("new-session", "-d", "-s", "plot", "-x", "80", "-y", "24", "env", *tmux_env,
         "sh", "-c", command)
    try:
        deadline = time.monotonic() + 90
        screen = ""
        while time.monotonic() < deadline:
            screen = tmux("capture-pane", "-p", "-t", "plot")
            dots = sum(1 for c in screen if 0x2800 < ord(c) <= 0x28FF)
            if "max  10" in screen and dots > 40:
                break
            time.sleep(0.5)
        lines = screen.splitlines()
        assert lines[0].split() == [WAVE, "geometry_msgs/msg/Point", "10", "s", "(w)",
                                    "arrival", "(t)", "live"]
        assert "max  10" in screen and f"■ {X}" in screen and f"■ {WAVE}/y" in screen, screen
        assert sum(1 for c in screen if 0x2800 < ord(c) <= 0x28FF) > 40, screen
        assert all(len(line) <= 80 for line in lines) and len(lines) <= 24
        tmux("send-keys", "-t", "plot", "q")
        deadline = time.monotonic() + 30
        while not status_file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert status_file.read_text().strip() == "0"
    finally:
        tmux("kill-server")
