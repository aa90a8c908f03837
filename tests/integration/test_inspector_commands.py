"""The inspector's session commands on a real session of real rclpy nodes: topics, hz,
echo, status with CPU and memory, parameter files, logger levels, and the rates and
resources streams a client watches.

One session serves the module (starting one costs seconds of DDS discovery on a busy
machine); each test asks it something different and leaves it as it found it.
"""

from __future__ import annotations

import asyncio
import json
import signal
import subprocess
import sys
import textwrap
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import pytest

from tuilaunch.client.link import Link
from tuilaunch.client.session_state import merged_usage
from tuilaunch.engine.ros.bridge import RosBridge
from tuilaunch.engine.ros.graph.topic_graph import full_node_name
from tuilaunch.engine.run.session.session_dir import SessionError
from tuilaunch.engine.run.vocabulary.requests import (
    EchoStart,
    EchoStop,
    Find,
    Start,
    Stop,
    Subscribe,
    WatchQos,
    WatchRates,
    WatchResources,
)

from ..conftest import run_cli, session_folders
from .inspector_helpers import NODE_SCRIPT
from .inspector_helpers import eventually as eventually_async
from .inspector_helpers import run as run_bridge
from .launch_world import make_package
from .session_steps import start_here, stop_here
from .test_sessions import wait_state

LAUNCH = """
from launch import LaunchDescription
from launch_ros.actions import Node


def node(name, *arguments):
    return Node(package='insp_nodes', executable='inspector_node', name=name,
                namespace='/insp', arguments=[name, *arguments])


def generate_launch_description():
    return LaunchDescription([
        node('fast', '--pub', 'scan', '--rate', '20', '--best-effort', '--params'),
        node('strict', '--sub', 'scan'),
        node('busy', '--burn', '0.3', '--logger-service', '--debug-ticks'),
        node('plain', '--pub', 'chatter', '--rate', '5', '--sub', 'orphan'),
        # named by its own code only: the launch learns its name from its log lines
        Node(package='insp_nodes', executable='inspector_node', namespace='/insp',
             arguments=['anon', '--pub', 'anon_topic', '--rate', '2']),
    ])
"""
FAST, STRICT, BUSY, PLAIN, ANON = "fast-1", "strict-2", "busy-3", "plain-4", "inspector_node-5"


def tl(*args: str, timeout: float = 120, env: dict[str, str] | None = None)\
        -> subprocess.CompletedProcess[str]:
    return run_cli(*args, timeout=timeout, env=env)


def together(*commands: tuple[str, ...]) -> list[subprocess.CompletedProcess[str]]:
    """The commands run at the same time (their waits overlap): their results, in order."""
    with ThreadPoolExecutor(len(commands)) as pool:
        return list(pool.map(lambda args: tl(*args), commands))


def ok(*args: str) -> str:
    done = tl(*args)
    assert done.returncode == 0, done.stderr
    return done.stdout


def one_line_error(done: subprocess.CompletedProcess[str], command: str) -> str:
    """A failed command's message: a non-zero exit, no traceback, `tuilaunch CMD: error:`."""
    assert done.returncode != 0, done.stdout
    assert "Traceback" not in done.stderr
    assert done.stderr.startswith(f"tuilaunch {command}: error: "), done.stderr
    return done.stderr.strip()


def eventually(check: Callable[[], Any], limit: float = 60.0) -> Any:
    end = time.monotonic() + limit
    while True:
        result = check()
        if result:
            return result
        assert time.monotonic() < end, f"condition never held: {check}"
        time.sleep(0.2)


@pytest.fixture(scope="module")
def session(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    root = tmp_path_factory.mktemp("inspector")
    prefix = root / "prefix"
    make_package(prefix, "insp_nodes", ["inspector_node"],
                 probe=f"#!{sys.executable}\n" + NODE_SCRIPT.read_text())
    (root / "inspect.launch.py").write_text(textwrap.dedent(LAUNCH))
    with session_folders(root / "log", prefix):
        # the module's setting, started and ended from this process: the commands tested
        # are the ones the tests run on it
        name = start_here(root / "inspect.launch.py", "--name", "insp")
        for process in (FAST, STRICT, BUSY, PLAIN, ANON):
            wait_state(name, process, "running")
        yield name
        stop_here(name)


def topics_of(name: str, *extra: str) -> dict[str, dict[str, Any]]:
    return {t["name"]: t for t in json.loads(ok("topics", name, "--json", *extra))["topics"]}


def test_topics_map_endpoints_to_processes_and_say_qos_problems(session):
    def settled() -> dict[str, dict[str, Any]] | None:
        topics = topics_of(session)
        scan = topics.get("/insp/scan", {})
        if [e["node"] for e in scan.get("publishers", [])] == ["/insp/fast"] and \
                [e["node"] for e in scan.get("subscribers", [])] == ["/insp/strict"]:
            return topics
        return None

    topics = eventually(settled)
    scan = topics["/insp/scan"]
    assert scan["types"] == ["std_msgs/msg/String"]
    (publisher,) = scan["publishers"]
    assert publisher["in_launch"] is True and publisher["process"] == FAST
    assert publisher["qos"]["reliability"] == "best_effort"
    assert scan["subscribers"][0]["process"] == STRICT
    (problem,) = scan["qos_problems"]
    assert "publisher /insp/fast and subscriber /insp/strict cannot talk" in problem
    assert "reliability" in problem
    # one node's topics, named by its process id
    assert set(topics_of(session, "--node", PLAIN)) >= {"/insp/chatter", "/insp/orphan"}
    assert "/insp/scan" not in topics_of(session, "--node", PLAIN)
    # a node the launch file does not name is still the launch's, by the name it logs under
    anon = eventually(lambda: topics_of(session).get("/insp/anon_topic"))
    assert [(e["node"], e["in_launch"], e["process"]) for e in anon["publishers"]] == \
        [("/insp/anon", True, ANON)]
    table = tl("topics", session, env={"COLUMNS": "60"}).stdout
    lines = table.split("\n\nQoS problems")[0].splitlines()
    assert lines[0].split() == ["TOPIC", "TYPE", "PUB", "SUB", "QOS"]
    assert all(len(line) <= 60 for line in table.splitlines())
    scan_line = next(line for line in lines if line.startswith("/insp/scan "))
    assert scan_line.split()[-3:] == ["1", "1", "!!"]  # one each way, and a QoS problem
    assert "std_msgs/" in scan_line
    assert "QoS problems" in table and "cannot talk" in table
    # -v: each endpoint with its node, process and QoS, as ros2 topic info -v
    verbose = ok("topics", session, "-v", "--node", FAST)
    scan_info = verbose.split("Topic: /insp/scan\n")[1].split("Topic: ")[0]
    assert "Type: std_msgs/msg/String" in scan_info
    assert "Publisher count: 1" in scan_info and "Subscription count: 1" in scan_info
    assert "Node name: fast\nNode namespace: /insp\nProcess: fast-1\n" in scan_info
    assert "Node name: strict\nNode namespace: /insp\nProcess: strict-2\n" in scan_info
    assert "  Reliability: BEST_EFFORT" in scan_info and "  Reliability: RELIABLE" in scan_info
    assert "QoS problem: " in scan_info


def test_hz_measures_a_known_rate_and_refuses_a_topic_nobody_publishes(session):
    # at once, as from several terminals: each measure is the server's own, and each refusal
    # waits out the server's wait for a publisher
    started = time.monotonic()
    measured, windowed, chatter, orphan, nowhere, unknown, bad = together(
        ("hz", session, "/insp/scan", "--duration", "3", "--json"),
        ("hz", session, "/insp/scan", "--duration", "2", "-w", "5", "--json"),
        ("hz", session, "insp/chatter", "--duration", "2"),
        ("hz", session, "/insp/orphan", "--duration", "1"),
        ("hz", session, "/insp/nowhere", "--duration", "1"),
        ("hz", "nosuch", "/insp/scan"),
        ("hz", session, "/insp/scan", "-w", "0"))
    assert measured.returncode == 0, measured.stderr
    result = json.loads(measured.stdout)
    assert result["topic"] == "/insp/scan"
    assert 10 < result["rate_hz"] < 30  # published at 20 Hz; loose: the machine is shared
    assert result["bytes_per_s"] > 0 and result["messages"] > 10
    assert 0 < result["min_s"] <= result["max_s"] and result["std_dev_s"] >= 0
    assert result["window"] == result["messages"] - 1  # periods between the messages
    assert result["size_min"] <= result["size_mean"] <= result["size_max"]
    # -w N: the figures over the last N periods, as ros2 topic hz -w
    assert windowed.returncode == 0, windowed.stderr
    assert json.loads(windowed.stdout)["window"] == 5
    assert chatter.returncode == 0, chatter.stderr
    lines = chatter.stdout.splitlines()
    assert lines[0].startswith("average rate: ")
    assert lines[1].startswith("\tmin: ") and " std dev: " in lines[1] and " window: " in \
        lines[1]
    assert lines[2].startswith("average bandwidth: ") and " messages" in lines[2]
    assert lines[3].startswith("\tmessage size mean: ")
    error = one_line_error(orphan, "hz")
    assert "topic /insp/orphan has no publisher (waited 5 s)" in error
    missing = one_line_error(nowhere, "hz")
    assert "no topic /insp/nowhere on the ROS graph" in missing
    assert time.monotonic() - started < 100  # never a hang (the deadlines are ~5 s each)
    assert "no running session named nosuch" in one_line_error(unknown, "hz")
    assert "--window 0 is not a positive number of messages" in one_line_error(bad, "hz")


def interrupted(args: list[str], ready: Callable[[str], bool]) -> tuple[int, str, str]:
    """Runs a command until its output satisfies `ready`, then Ctrl+C (SIGINT) as a terminal
    sends it: its exit status, its whole output and its errors."""
    command = subprocess.Popen([sys.executable, "-m", "tuilaunch", *args],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert command.stdout is not None
        out = ""
        end = time.monotonic() + 120
        while not ready(out):
            assert time.monotonic() < end, out
            line = command.stdout.readline()
            assert line, f"it ended: {out}"
            out += line
        command.send_signal(signal.SIGINT)
        # read on from the same buffered stream (communicate() would skip what it holds)
        rest = command.stdout.read()
        assert command.stderr is not None
        errors = command.stderr.read()
        return command.wait(timeout=60), out + rest, errors
    finally:
        if command.poll() is None:
            command.kill()
            command.wait()


def test_hz_streams_a_block_a_second_until_ctrl_c_then_says_the_figures(session):
    status, out, errors = interrupted(["hz", session, "/insp/scan"],
                                      lambda out: out.count("average rate: ") >= 2)
    assert status == 0 and errors == ""
    blocks = out.split("average rate: ")[1:]
    assert len(blocks) >= 2  # two streamed; at Ctrl+C, the figures now if they are newer
    counts = []
    for block in blocks:
        rate = float(block.split("\n")[0])
        assert 10 < rate < 30
        assert "\tmin: " in block and "average bandwidth: " in block
        counts.append(int(block.split(" from ")[1].split()[0]))
    # each block says more messages than the one before it: none is a repeat
    assert counts == sorted(set(counts)), out


def test_echo_prints_count_messages_as_yaml(session):
    out = ok("echo", session, "/insp/chatter", "--count", "2", "--timeout", "60")
    documents = [d for d in out.split("---\n") if d.strip()]
    assert len(documents) == 2 and out.endswith("---\n")
    assert all(d.startswith("data: hello ") for d in documents)
    once = ok("echo", session, "/insp/chatter", "--once")
    assert once.count("---\n") == 1 and once.startswith("data: hello ")


def test_echo_runs_until_ctrl_c_and_honours_its_timeout(session):
    status, out, errors = interrupted(["echo", session, "/insp/chatter"],
                                      lambda out: out.count("---\n") >= 3)
    assert status == 130 and errors == "tuilaunch: interrupted\n"
    assert out.count("data: hello ") >= 3
    orphan, timed = together(("echo", session, "/insp/orphan", "--timeout", "2"),
                             ("echo", session, "/insp/chatter", "--timeout", "3"))
    # --timeout is the whole wait, the publisher's included
    error = one_line_error(orphan, "echo")
    assert "topic /insp/orphan has no publisher (waited 2 s)" in error
    # no count: what came within the time is enough
    assert timed.returncode == 0 and "data: hello " in timed.stdout


def test_status_shows_cpu_memory_and_threads_per_process(session):
    status = json.loads(ok("status", session, "--json"))
    busy = next(p for p in status["processes"] if p["id"] == BUSY)
    assert busy["cpu_percent"] > 5  # it keeps ~30 % of a core busy
    assert busy["rss_bytes"] > 10 << 20  # an rclpy process holds tens of MB
    assert busy["threads"] >= 2  # its burner besides the main thread
    plain = next(p for p in status["processes"] if p["id"] == PLAIN)
    assert plain["cpu_percent"] is not None and plain["threads"] >= 1
    table = ok("status", session)
    assert "CPU%" in table and "RSS" in table and "THREADS" in table


def test_params_dump_then_load_round_trip(session, tmp_path):
    with ThreadPoolExecutor(1) as pool:
        # meanwhile: a node nobody runs, refused once the server's wait for it is over
        ghost = pool.submit(tl, "params", session, "/ghost", "--dump")
        round_trip(session, tmp_path)
        assert "no node /ghost on the ROS graph" in one_line_error(ghost.result(), "params")


def round_trip(session: str, tmp_path: Path) -> None:
    dumped = ok("params", session, FAST, "--dump")
    assert dumped.startswith("/insp/fast:\n  ros__parameters:\n")
    assert "label: lidar" in dumped and "p: 1.5" in dumped
    changed = tmp_path / "fast.yaml"
    changed.write_text(dumped.replace("label: lidar", "label: radar"))
    loaded = tl("params", session, "/insp/fast", "--load", str(changed))
    assert loaded.returncode == 0, loaded.stdout + loaded.stderr
    assert "label: set" in loaded.stdout.splitlines()
    assert "label: radar" in ok("params", session, FAST, "--dump")
    wrong = tmp_path / "broken.yaml"
    wrong.write_text("a: [")
    error = one_line_error(tl("params", session, FAST, "--load", str(wrong)), "params")
    assert f"parameter file {wrong}:" in error and "not valid YAML" in error
    nobody = one_line_error(tl("params", session, "nobody", "--dump"), "params")
    assert "no node or process 'nobody'" in nobody


def test_log_level_through_the_logger_service_or_says_how_to_restart(session):
    with ThreadPoolExecutor(1) as pool:
        # meanwhile: a node with no logger service, refused once the server's wait for its
        # service is over
        plain = pool.submit(tl, "log-level", session, PLAIN, "debug")
        ok("log-level", session, "/insp/busy", "debug")
        eventually(lambda: "debug tick" in ok("logs", session, BUSY))
        ok("log-level", session, BUSY, "info")
        error = one_line_error(plain.result(), "log-level")
    assert "/insp/plain has no logger service" in error
    assert f"tuilaunch restart {session} {PLAIN} --log-level DEBUG" in error
    bad = one_line_error(tl("log-level", session, BUSY, "loud"), "log-level")
    assert "'loud' is not a logger level" in bad


def events_until(link: Link, kind: str, check: Callable[[dict[str, Any]], bool],
                 limit: float = 60.0) -> dict[str, Any]:
    end = time.monotonic() + limit
    link.timeout = limit
    for message in link.messages():
        for event in message.get("events") or []:
            if event["kind"] == kind and check(event["data"]):
                return event
        assert time.monotonic() < end, f"no {kind} event as wanted"
    raise AssertionError("the session closed the connection")


def events_for(link: Link, seconds: float) -> list[dict[str, Any]]:
    """The events that arrive within `seconds` (to count them, or show that none of a kind
    comes): a request after the wait brings every event sent before its reply."""
    time.sleep(seconds)
    link.request(Find(process=FAST))
    found = [e for message in link.pending for e in message.get("events") or []]
    link.pending.clear()
    return found


def test_a_watching_client_gets_rates_and_resources_until_it_stops(session):
    link = Link(session, timeout=60)
    try:
        link.request(Subscribe(max_lines=1, kinds=["rates", "resources"]))
        answer = link.request(WatchRates(topics=["/insp/scan", "/insp/orphan"]))
        assert answer["unmeasured"] == {"/insp/orphan": "topic /insp/orphan has no publisher"}
        event = events_until(link, "rates",
                             lambda d: (d["/insp/scan"]["rate_hz"] or 0) > 5)
        assert event["data"]["/insp/orphan"] == {"rate_hz": None, "bytes_per_s": None}
        link.request(WatchResources(on=True))
        # the first event has every figure; the next ones only those that moved
        event = events_until(link, "resources", lambda d: BUSY in d)
        assert set(event["data"][BUSY]) == {"cpu_percent", "rss_bytes", "threads", "growing"}
        if (event["data"][BUSY]["cpu_percent"] or 0) <= 5:
            events_until(link, "resources",
                         lambda d: (d.get(BUSY, {}).get("cpu_percent") or 0) > 5)
        link.request(WatchRates(topics=[]))
        link.request(WatchResources(on=False))
        stopped = time.time()
        late = [e for e in events_for(link, 3.0) if e["time"] > stopped]
        assert late == []
    finally:
        link.close()


def test_a_watcher_is_sent_the_figures_of_the_processes_it_shows_only(session):
    """A TUI whose tree is too narrow for the CPU column shows the selected node's figures
    only: the others' do not cross the link, their growing-memory mark does; when the
    selection moves, the new one's figures come at once and the old one's are taken back."""
    link = Link(session, timeout=60)
    try:
        link.request(Subscribe(max_lines=1, kinds=["resources"]))
        link.request(WatchResources(on=True, processes=[BUSY]))
        first = events_until(link, "resources", lambda d: BUSY in d)["data"]
        assert set(first[BUSY]) == {"cpu_percent", "rss_bytes", "threads", "growing"}
        assert first[FAST] == {"growing": False}
        for event in [e for e in events_for(link, 2.5) if e["kind"] == "resources"]:
            assert set(event["data"]) <= {BUSY}, event  # the others' figures stay home
        link.request(WatchResources(on=True, processes=[FAST]))
        moved = events_until(link, "resources", lambda d: FAST in d)["data"]
        assert moved[FAST]["rss_bytes"] > 0 and moved[FAST]["threads"] >= 1
        assert moved[BUSY] == {"cpu_percent": None, "rss_bytes": None, "threads": None}
        link.request(WatchResources(on=True, processes=None))  # the tree grew wide
        every = events_until(link, "resources", lambda d: BUSY in d)["data"]
        assert every[BUSY]["rss_bytes"] > 0 and every[BUSY]["cpu_percent"] is not None
        link.request(WatchResources(on=False))
    finally:
        link.close()


def test_the_tui_keeps_the_growing_mark_of_a_process_whose_figures_it_does_not_show():
    """What the TUI holds of those events: a process no longer shown keeps `↑mem` and
    loses its figures (none stale on screen), a stopped one is forgotten."""
    held = {"a": {"cpu_percent": 3.0, "rss_bytes": 1 << 20, "threads": 4, "growing": True},
            "b": {"cpu_percent": 0.0, "rss_bytes": 1 << 20, "threads": 2, "growing": False},
            "c": {"cpu_percent": 1.0, "rss_bytes": 1 << 20, "threads": 2, "growing": False}}
    hidden = {"cpu_percent": None, "rss_bytes": None, "threads": None}
    stopped = {**hidden, "growing": False}
    usage = merged_usage(held, {"a": hidden, "b": hidden, "c": stopped,
                                "d": {"growing": True}})
    assert usage == {"a": {**hidden, "growing": True}, "d": {"growing": True}}
    assert merged_usage(usage, {"a": {"cpu_percent": 5.0, "rss_bytes": 2 << 20,
                                      "threads": 4}})["a"]["rss_bytes"] == 2 << 20


def test_a_qos_watcher_is_told_the_problems_when_they_change_and_only_then(session):
    """`watch_qos`: the server checks the graph where the nodes run and tells a watching
    client the QoS problems at once, then only when they change: nothing while they stay
    as they are, and that the problem is gone when one node of the pair stops."""

    def scan_problem(data: dict[str, Any]) -> bool:
        return any(t["name"] == "/insp/scan" and t["qos_problems"] for t in data["topics"])

    link = Link(session, timeout=60)
    try:
        link.request(Subscribe(max_lines=1, kinds=["qos"]))
        link.request(WatchQos(on=True))
        told = events_until(link, "qos", scan_problem)
        (scan,) = [t for t in told["data"]["topics"] if t["name"] == "/insp/scan"]
        assert "publisher /insp/fast and subscriber /insp/strict cannot talk" in \
            scan["qos_problems"][0]
        # a check runs every 5 s: what did not change is not sent again
        assert [e for e in events_for(link, 6.0) if e["data"] == told["data"]] == []
        link.request(Stop(process=STRICT))
        events_until(link, "qos", lambda data: not scan_problem(data))
        link.request(Start(process=STRICT))
        events_until(link, "qos", scan_problem)
        link.request(WatchQos(on=False))
    finally:
        link.close()
        wait_state(session, STRICT, "running")  # as the module's session was


def test_an_echo_stream_is_throttled_per_client_and_stops_when_asked(session):
    link = Link(session, timeout=60)
    try:
        with pytest.raises(SessionError, match="subscribe first"):
            link.request(EchoStart(topic="/insp/scan"))
        link.request(Subscribe(max_lines=1, kinds=["echo"]))
        link.request(EchoStart(topic="/insp/scan", max_per_s=2))
        first = events_until(link, "echo", lambda d: d["topic"] == "/insp/scan")
        assert first["data"]["text"].startswith("data: hello ")
        # 20 messages a second are published; a screen is sent at most 2 of them
        shown = [e for e in events_for(link, 3.0) if e["kind"] == "echo"]
        assert 1 <= len(shown) <= 8
        link.request(EchoStop(topic="/insp/scan"))
        stopped = time.time()
        assert [e for e in events_for(link, 2.0) if e["time"] > stopped] == []
    finally:
        link.close()


async def server_subscribes(bridge: RosBridge, topics: list[str], wanted: bool) -> None:
    """Waits until the session's bridge (node /tuilaunch_PID) subscribes to each topic, or to
    none of them, as another node on the graph sees it."""
    async def check() -> bool:
        for topic in topics:
            infos = await asyncio.to_thread(bridge.node.get_subscriptions_info_by_topic,
                                            topic)
            if any(full_node_name(i.node_name, i.node_namespace).startswith("/tuilaunch_")
                   for i in infos) != wanted:
                return False
        return True
    await eventually_async(check, 60, f"the server subscribed={wanted} to {topics}")


def test_a_client_that_leaves_stops_its_rates_and_echo_measurements(session):
    topics = ["/insp/chatter", "/insp/scan"]

    async def scenario(bridge: RosBridge) -> None:
        # one bridge throughout: a new one would see an empty graph for a while
        link = await asyncio.to_thread(Link, session, 60)
        try:
            await asyncio.to_thread(link.request, Subscribe(max_lines=1,
                                                            kinds=["echo", "rates"]))
            await asyncio.to_thread(link.request, WatchRates(topics=["/insp/chatter"]))
            await asyncio.to_thread(link.request, EchoStart(topic="/insp/scan"))
            await server_subscribes(bridge, topics, True)
        finally:
            link.close()  # no unwatch, no echo_stop: the connection just ends
        await server_subscribes(bridge, topics, False)

    run_bridge(scenario)


def test_a_node_named_in_its_code_is_named_like_a_process_id(session):
    """/insp/anon: the launch file gives no name; once its log lines said it, the full
    name works for wait, logs and status as the process id does."""
    eventually(lambda: "/insp/anon" in ok("topics", session, "-v", "--node", ANON))
    assert ok("wait", session, "/insp/anon", "running", "--timeout", "30") == ""
    first = ok("logs", session, "/insp/anon").splitlines()[0]
    assert first == ok("logs", session, ANON).splitlines()[0]
    assert first.startswith(f"[INFO] [{ANON}]: process started with pid [")
    unknown = one_line_error(tl("wait", session, "/insp/nobody", "running"), "wait")
    assert "no process '/insp/nobody'" in unknown
