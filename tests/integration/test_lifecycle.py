"""Lifecycle nodes: plans of launch_ros's lifecycle API, and real rclpy lifecycle nodes run."""

from __future__ import annotations

import asyncio
import json
import os
import re
from pathlib import Path

import pytest

from tuilaunch.engine import load_file, resolve
from tuilaunch.engine.errors import LaunchError
from tuilaunch.engine.launcher import make_supervisor
from tuilaunch.engine.run.supervisor.supervisor import Event

from ..conftest import plan_of, run_cli, run_headless

HEADER = """\
from launch import LaunchDescription
from launch.actions import EmitEvent, RegisterEventHandler, LogInfo
from launch.events import matches_action
from launch_ros.actions import LifecycleNode, Node
from launch_ros.events.lifecycle import ChangeState
from launch_ros.event_handlers import OnStateTransition
from lifecycle_msgs.msg import Transition
"""

# the pattern of ros2 demos' lifecycle launch file: configure at start, activate once inactive
CONFIGURE_THEN_ACTIVATE = HEADER + """
talker = LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker',
                       name='lc_talker', namespace='demo', parameters=[{'rate': 20.0}])
configure = EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_action(talker),
                                        transition_id=Transition.TRANSITION_CONFIGURE))
on_inactive = RegisterEventHandler(OnStateTransition(
    target_lifecycle_node=talker, goal_state='inactive',
    entities=[LogInfo(msg='talker is inactive, activating'),
              EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_action(talker),
                                          transition_id=Transition.TRANSITION_ACTIVATE))]))
def generate_launch_description():
    return LaunchDescription([on_inactive, talker, configure])
"""




# --- plans -------------------------------------------------------------------------------


def test_change_state_targets_the_matched_node_and_state_handler_waits_for_it(write):
    plan = plan_of(write(CONFIGURE_THEN_ACTIVATE))
    (talker,) = plan.processes
    assert talker.lifecycle and not talker.autostart
    assert talker.full_name == "/demo/lc_talker"
    by_kind = {}
    for action in plan.actions:
        by_kind.setdefault(action.kind, []).append(action)
    configure, activate = sorted(by_kind["lifecycle_transition"],
                                 key=lambda a: a.data["transitions"][0] != "configure")
    assert configure.data["transitions"] == ["configure"]
    assert configure.data["targets"] == [talker.id]
    assert configure.trigger is None  # at launch start, as EmitEvent runs
    assert activate.data["targets"] == [talker.id]
    assert activate.trigger.to_json() == {"on": "state", "target": talker.id, "delay": 0.0,
                                          "io": "*|*|inactive"}
    assert activate.target == "/demo/lc_talker"


def test_print_names_the_transitions_and_the_state_they_wait_for(write):
    result = run_cli(str(write(CONFIGURE_THEN_ACTIVATE)), "--print")
    assert result.returncode == 0, result.stderr
    assert "configure /demo/lc_talker" in result.stdout
    assert "activate /demo/lc_talker" in result.stdout
    assert "when lc_talker-1 reaches inactive" in result.stdout
    assert "/demo/lc_talker  [lc_talker-1] (tuilaunch_demos/lifecycle_talker) lifecycle\n" \
        in result.stdout
    data = json.loads(run_cli(str(write(CONFIGURE_THEN_ACTIVATE)), "--print", "--json").stdout)
    assert data["processes"][0]["lifecycle"] is True


def test_matches_node_name_lifecycle_transition_and_autostart(write):
    path = write(HEADER + """
from launch_ros.actions import LifecycleTransition
from launch_ros.events import matches_node_name
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
a = LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker', name='a',
                  namespace='', autostart=LaunchConfiguration('auto'))
b = LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker', name='b',
                  namespace='/robot')
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('auto', default_value='true'),
        a, b,
        EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_node_name('robot/b'),
                                    transition_id=Transition.TRANSITION_CONFIGURE)),
        EmitEvent(event=ChangeState(
            lifecycle_node_matcher=lambda node: node.node_name.startswith('/robot'),
            transition_id=Transition.TRANSITION_CLEANUP)),
        EmitEvent(event=ChangeState(lifecycle_node_matcher=lambda action: action is a,
                                    transition_id=Transition.TRANSITION_ACTIVATE)),
        LifecycleTransition(lifecycle_node_names=['/robot/b', 'a'],
                            transition_ids=[Transition.TRANSITION_CONFIGURE,
                                            Transition.TRANSITION_ACTIVATE]),
    ])
""")
    plan = plan_of(path)
    a, b = plan.processes
    assert a.autostart and not b.autostart
    assert not plan_of(path, auto="false").processes[0].autostart
    by_name, by_function, by_identity, sequence = plan.actions
    assert by_name.data["targets"] == [b.id]
    assert by_function.data["targets"] == [b.id]
    assert by_identity.data["targets"] == [a.id]
    assert sequence.data["transitions"] == ["configure", "activate"]
    assert sequence.data["targets"] == [a.id, b.id]


def test_bad_transition_and_nameless_lifecycle_node_name_the_line(write):
    path = write(HEADER + """
node = LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker', name='n',
                     namespace='')
def generate_launch_description():
    return LaunchDescription([node, EmitEvent(event=ChangeState(
        lifecycle_node_matcher=matches_action(node), transition_id=42))])
""")
    with pytest.raises(LaunchError) as caught:
        plan_of(path)
    assert "transition_id=42" in caught.value.message
    assert caught.value.origin is not None and caught.value.origin.line == 12
    nameless = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([LifecycleNode(package='tuilaunch_demos',
                                            executable='lifecycle_talker', namespace='')])
""", "nameless.py")
    result = run_cli(str(nameless), "--print")
    assert result.returncode != 0
    assert "LifecycleNode() needs a name" in result.stderr
    assert "nameless.py:10" in result.stderr
    assert "Traceback" not in result.stderr


def test_a_transition_matching_no_node_is_a_warning(write):
    path = write(HEADER + """
from launch_ros.events import matches_node_name
def generate_launch_description():
    return LaunchDescription([EmitEvent(event=ChangeState(
        lifecycle_node_matcher=matches_node_name('/nobody'),
        transition_id=Transition.TRANSITION_CONFIGURE))])
""")
    plan = plan_of(path)
    assert any("matches no lifecycle node" in w and "/nobody" in w for w in plan.warnings)


def test_nav2_style_lifecycle_manager_is_a_plain_node_with_typed_parameters(
        write, tmp_path, monkeypatch):
    prefix = fake_lifecycle_manager_prefix(tmp_path)
    monkeypatch.setenv("AMENT_PREFIX_PATH",
                       f"{prefix}{os.pathsep}{os.environ.get('AMENT_PREFIX_PATH', '')}")
    plan = plan_of(write(NAV2_STYLE))
    assert not plan.problems()
    manager = next(p for p in plan.processes if p.name == "lifecycle_manager_test")
    assert not manager.lifecycle
    assert manager.parameters == {"autostart": True, "node_names": ["first", "second"],
                                  "bond_timeout": 0.0}
    assert {p.full_name for p in plan.processes if p.lifecycle} == {"/first", "/second"}


NAV2_STYLE = """
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import LifecycleNode, Node

def generate_launch_description():
    autostart = LaunchConfiguration('autostart')
    nodes = ['first', 'second']
    return LaunchDescription([
        DeclareLaunchArgument('autostart', default_value='true'),
        *[LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker', name=n,
                        namespace='', parameters=[{'rate': 20.0}]) for n in nodes],
        Node(package='nav2_lifecycle_manager', executable='lifecycle_manager',
             name='lifecycle_manager_test', output='screen',
             parameters=[{'autostart': autostart, 'node_names': nodes,
                          'bond_timeout': 0.0}]),
    ])
"""

# A test double for nav2's lifecycle manager (a C++ node, not installable here): reads the
# same parameters and drives the nodes through the same services.
FAKE_MANAGER = """#!/usr/bin/env python3
import sys
import rclpy
from rclpy.node import Node
from lifecycle_msgs.srv import ChangeState

rclpy.init(args=sys.argv)
node = Node('lifecycle_manager')
names = node.declare_parameter('node_names', ['']).value
autostart = node.declare_parameter('autostart', False).value
node.declare_parameter('bond_timeout', 4.0)
if autostart:
    for transition in (1, 3):
        for name in names:
            client = node.create_client(ChangeState, f'/{name}/change_state')
            client.wait_for_service()
            request = ChangeState.Request()
            request.transition.id = transition
            future = client.call_async(request)
            rclpy.spin_until_future_complete(node, future)
            print(f'manager: {name} transition {transition} ->',
                  future.result().success, flush=True)
print('manager: all managed nodes are active', flush=True)
try:
    rclpy.spin(node)
except Exception:
    pass
"""


def fake_lifecycle_manager_prefix(tmp_path: Path) -> Path:
    return fake_package_prefix(tmp_path, "nav2_lifecycle_manager", "lifecycle_manager",
                               FAKE_MANAGER)


def fake_package_prefix(tmp_path: Path, pkg: str, executable: str, text: str) -> Path:
    """An install prefix holding package `pkg` with one Python executable."""
    prefix = tmp_path / "prefix"
    (prefix / "share/ament_index/resource_index/packages").mkdir(parents=True)
    (prefix / "share/ament_index/resource_index/packages" / pkg).write_text("")
    (prefix / "share" / pkg).mkdir(parents=True)
    (prefix / "share" / pkg / "package.xml").write_text(f"<package><name>{pkg}</name></package>")
    exe = prefix / "lib" / pkg / executable
    exe.parent.mkdir(parents=True)
    exe.write_text(text)
    exe.chmod(0o755)
    return prefix


# --- real lifecycle nodes ------------------------------------------------------------------


def test_configure_then_activate_on_inactive_with_a_real_lifecycle_node(write):
    out = run_headless(write(CONFIGURE_THEN_ACTIVATE),
                       until=('Publishing: "hello 3"', "lifecycle state active",
                              "activate done"))
    lines = out.splitlines()

    def first(text: str) -> int:
        return next(i for i, line in enumerate(lines) if text in line)

    # the handler runs on the state tuilaunch saw; the node publishes only once active
    # (how soon tuilaunch hears "active" against the node's first publication is a race, and
    # so is the transition event against the service's reply: the test waits for both)
    assert first("lifecycle state inactive") < first("talker is inactive, activating")
    assert first("configure done") < first("activate done")
    assert "[INFO] [lc_talker-1]: lifecycle state active" in out
    assert first("]: configured") < first("]: activated") < first('Publishing: "hello 1"')


# deactivated once it is active (handle_once), the node reaches inactive again: launch_ros
# runs the inactive handler on every matching transition, so it is activated a second time
CYCLE = HEADER + """
talker = LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker',
                       name='cycler', namespace='', parameters=[{'rate': 20.0}])
def change(transition):
    return EmitEvent(event=ChangeState(lifecycle_node_matcher=matches_action(talker),
                                       transition_id=transition))
def generate_launch_description():
    return LaunchDescription([
        RegisterEventHandler(OnStateTransition(
            target_lifecycle_node=talker, goal_state='inactive',
            entities=[LogInfo(msg='inactive: activating'),
                      change(Transition.TRANSITION_ACTIVATE)])),
        RegisterEventHandler(OnStateTransition(
            target_lifecycle_node=talker, goal_state='active', handle_once=True,
            entities=[LogInfo(msg='active: deactivating once'),
                      change(Transition.TRANSITION_DEACTIVATE)])),
        talker, change(Transition.TRANSITION_CONFIGURE)])
"""


def test_a_state_handler_runs_on_every_matching_transition_unless_handle_once(write):
    def twice_active(out: str) -> bool:
        second = out.split("inactive: activating", 2)
        return len(second) == 3 and "lifecycle state active" in second[2]

    out = run_headless(write(CYCLE), until=twice_active)
    assert out.count("inactive: activating") == 2, out
    assert out.count("active: deactivating once") == 1, out
    assert twice_active(out), out
    # the second activation came after the deactivation the once-handler asked for
    assert out.index("active: deactivating once") < out.rindex("inactive: activating")


def test_autostart_activates_and_a_refused_transition_says_so(write):
    path = write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker', name='auto',
                      namespace='', autostart=True, parameters=[{'rate': 20.0}]),
        LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker', name='stuck',
                      namespace='', autostart=True, parameters=[{'fail_configure': True}]),
    ])
""")
    out = run_headless(path, until=("[auto]: Publishing", "refused transition",
                                    "[INFO] [auto-1]: lifecycle state active"))
    assert "[INFO] [auto-1]: lifecycle state active" in out
    assert re.search(r"\[ERROR\] \[stuck-2\]: /stuck refused transition 'configure' "
                     r"\(autostart, \S*test_launch\.py:\d+\); it is unconfigured", out), out
    assert "[INFO] [stuck-2]: lifecycle state active" not in out
    assert "[auto-1]" in out and 'Publishing: "hello' in out


def test_nav2_style_manager_drives_the_nodes_and_tuilaunch_follows(write, tmp_path):
    prefix = fake_lifecycle_manager_prefix(tmp_path)
    env = {"AMENT_PREFIX_PATH": f"{prefix}{os.pathsep}{os.environ.get('AMENT_PREFIX_PATH', '')}"}
    followed = ("[INFO] [first-1]: lifecycle state active",
                "[INFO] [second-2]: lifecycle state active")
    out = run_headless(write(NAV2_STYLE), until=("all managed nodes are active", *followed),
                       env=env)
    assert "manager: first transition 3 -> True" in out
    assert "manager: second transition 3 -> True" in out
    for line in followed:
        assert line in out, out


async def test_operator_transitions_follow_the_live_state(write, tmp_path):
    # its own parameter folder: a run removes its folder at the end
    plan = resolve(load_file(str(write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        LifecycleNode(package='tuilaunch_demos', executable='lifecycle_talker', name='op',
                      namespace='', autostart=True)])
"""))), {}, tmp_path / "params")
    supervisor = make_supervisor(plan, tmp_path / "log", sigterm_timeout=3)
    events: list[Event] = []
    supervisor.subscribe(events.append)
    states = asyncio.Queue[str]()
    supervisor.subscribe(lambda e: states.put_nowait(e.reason or "")
                         if e.kind == "lifecycle" else None)
    run = asyncio.ensure_future(supervisor.run())
    (proc,) = plan.processes

    async def reach(state: str) -> None:
        while await asyncio.wait_for(states.get(), 60) != state:
            pass

    try:
        await reach("active")
        assert await supervisor.lifecycle.request(proc.id, "deactivate")
        await reach("inactive")
        assert supervisor.lifecycle.states[proc.id] == "inactive"
        # not from inactive: refused before it reaches the node (an rclpy node dies of it)
        assert not await supervisor.lifecycle.request(proc.id, "deactivate")
        assert any(e.kind == "log" and e.reason == "cannot deactivate /op: it is inactive "
                   "(it can activate, cleanup, inactive_shutdown)" for e in events)
        assert await supervisor.lifecycle.request(proc.id, "inactive_shutdown")
        await reach("finalized")
    finally:
        await supervisor.shutdown("test over")
        await asyncio.wait_for(run, 30)
    assert proc.id not in supervisor.lifecycle.states  # exited: no state any more


# A lifecycle node that is slow, as on a busy machine: its services are on the graph at once,
# but it serves them only a few seconds later, and its configure takes seconds too.
SLOW_NODE = """#!/usr/bin/env python3
import sys
import time
import rclpy
from rclpy.lifecycle import Node, TransitionCallbackReturn


class Slow(Node):
    def on_configure(self, state):
        time.sleep(3)  # the behaviour under test: a transition longer than the timeout
        return TransitionCallbackReturn.SUCCESS


rclpy.init(args=sys.argv)
node = Slow('slow')
print('slow: services up, busy for 4 s', flush=True)
time.sleep(4)  # the behaviour under test: a node that answers late
rclpy.spin(node)
"""


async def test_autostart_survives_calls_that_outlast_the_service_timeout(
        write, tmp_path, monkeypatch):
    prefix = fake_package_prefix(tmp_path, "slow_lifecycle", "slow", SLOW_NODE)
    monkeypatch.setenv("AMENT_PREFIX_PATH",
                       f"{prefix}{os.pathsep}{os.environ.get('AMENT_PREFIX_PATH', '')}")
    plan = resolve(load_file(str(write(HEADER + """
def generate_launch_description():
    return LaunchDescription([
        LifecycleNode(package='slow_lifecycle', executable='slow', name='slow',
                      namespace='', autostart=True)])
"""))), {}, tmp_path / "params")
    # its first get_state and its configure outlast this timeout: the tracker asks the
    # state again, and learns how configure ended from the node's transition events
    supervisor = make_supervisor(plan, tmp_path / "log", sigterm_timeout=3, service_timeout=1)
    events: list[Event] = []
    supervisor.subscribe(events.append)
    active = asyncio.Event()
    # the activate's outcome is said after the state event: wait for the words, not the state
    supervisor.subscribe(lambda e: active.set()
                         if e.kind == "log" and "/slow: activate done" in (e.reason or "")
                         else None)
    run = asyncio.ensure_future(supervisor.run())
    try:
        await asyncio.wait_for(active.wait(), 60)
    except TimeoutError:
        pytest.fail(f"/slow never became active: {[e.reason for e in events]}")
    finally:
        await supervisor.shutdown("test over")
        await asyncio.wait_for(run, 30)
    logs = [e.reason or "" for e in events if e.kind == "log"]
    assert any("no answer yet from /slow/get_state" in line for line in logs), logs
    # no answer in time (on a busy machine the service may not even be ready in time): the
    # outcome came from the node's transition events, and the missing answer was said
    assert any(line.startswith("configure /slow: service /slow/change_state ")
               and "transition events tell the outcome" in line for line in logs), logs
    assert any("/slow: configure done (autostart" in line for line in logs), logs
    assert any("/slow: activate done (autostart" in line for line in logs), logs
    assert not any("unknown" in line for line in logs), logs


async def test_a_state_handler_reruns_for_a_transition_made_while_it_was_still_running(
        write, tmp_path):
    """The node reaches inactive again before the answer to the handler's activate came
    (a reply late on a busy machine): that second transition still runs the handler again,
    as launch_ros runs it on each matching transition event."""
    from tuilaunch.engine.describe.lifecycle import state_keys
    from tuilaunch.engine.run.plugins import Plugin
    from tuilaunch.engine.run.supervisor.supervisor import Supervisor

    plan = resolve(load_file(str(write(CONFIGURE_THEN_ACTIVATE))), {}, tmp_path / "params")
    (talker,) = plan.processes
    asked: list[list[str]] = []
    answer = asyncio.Event()

    class LateAnswers(Plugin):  # stands for the lifecycle tracker, with a late reply
        def actions(self):  # type: ignore[no-untyped-def]
            return {"lifecycle_transition": self.transition}

        async def transition(self, action):  # type: ignore[no-untyped-def]
            asked.append(action.data["transitions"])
            if action.data["transitions"] == ["activate"] and len(asked) == 2:
                await answer.wait()  # the first activate: answered after the cycle below
            return True

    supervisor = Supervisor(plan, tmp_path / "log", sigterm_timeout=3)
    supervisor.add_plugin(LateAnswers())

    def reached(transition: str, start: str, goal: str) -> None:
        for key in state_keys(transition, start, goal):
            supervisor.state_reached(talker.id, "state:" + key)
            supervisor.state_reached("*", "state:" + key)

    async def until(condition, what: str) -> None:  # type: ignore[no-untyped-def]
        deadline = asyncio.get_running_loop().time() + 30
        while not condition():
            assert asyncio.get_running_loop().time() < deadline, f"{what}: {asked}"
            await asyncio.sleep(0.02)

    run = asyncio.ensure_future(supervisor.run(keep_alive=True))
    try:
        await until(lambda: asked == [["configure"]], "configure was never asked")
        reached("configure", "unconfigured", "inactive")
        await until(lambda: len(asked) == 2, "the inactive handler never ran")
        # while the activate waits for its answer, the node goes active and back
        reached("activate", "inactive", "active")
        reached("deactivate", "active", "inactive")
        answer.set()
        await until(lambda: len(asked) == 3, "the second inactive was missed")
        assert asked == [["configure"], ["activate"], ["activate"]]
    finally:
        await supervisor.shutdown("test over")
        await asyncio.wait_for(run, 30)
