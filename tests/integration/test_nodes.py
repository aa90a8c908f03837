"""`sl.node(...)`: what reaches the process's argv and parameter files."""

from __future__ import annotations

import yaml

from ..conftest import EXAMPLES, plan_of

HEADER = "from simple_launch import SimpleLauncher\n"


def test_full_argv_has_name_namespace_params_file_and_remaps(write):
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher()
    with sl.group(ns='r1'):
        sl.node('tuilaunch_demos', 'talker', name='t', arguments='--one two',
                remappings={'chatter': 'news'}, ros_arguments=['--log-level', 'debug'],
                parameters={'rate': 5.0})
    return sl.launch_description()
""")
    proc = plan_of(path).processes[0]
    assert proc.cmd[0].endswith("lib/tuilaunch_demos/talker")
    assert proc.cmd[1:3] == ["--one", "two"]  # a string of arguments is split
    # as launch_ros builds it: the user's ros_arguments in their own --ros-args block, then
    # another for the name, namespace, parameters and remappings
    ros = proc.cmd[proc.cmd.index("--ros-args") + 1:]
    assert ros[:3] == ["--log-level", "debug", "--ros-args"]
    assert ["-r", "__node:=t"] == ros[3:5] and ["-r", "__ns:=/r1"] == ros[5:7]
    assert ros[7] == "--params-file" and ros[8].endswith("t-1.yaml")
    assert ros[9:] == ["-r", "chatter:=news"]
    assert proc.remappings == [["chatter", "news"]]


def test_parameters_merge_in_order_with_types_and_yaml_files_keep_their_place(write):
    user_yaml = EXAMPLES / "tuilaunch_demos" / "config" / "talker.yaml"
    path = write(HEADER + f"""
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('rate', 3)
    sl.declare_arg('on', True)
    sl.node('tuilaunch_demos', 'talker', parameters=[
        {{'rate': 1.0, 'message': 'first', 'nested': {{'a': 1, 'b': [1.5, 2.5]}}}},
        '{user_yaml}',
        {{'rate': sl.arg('rate'), 'flag': sl.arg('on'), 'name': sl.arg('on') + 'x'}},
    ])
    return sl.launch_description()
""")
    proc = plan_of(path).processes[0]
    assert proc.parameters == {"rate": 3, "message": "first", "nested.a": 1,
                               "nested.b": [1.5, 2.5], "flag": True, "name": "Truex"}
    assert proc.parameter_files == [str(user_yaml)]
    files = [proc.cmd[i + 1] for i, a in enumerate(proc.cmd) if a == "--params-file"]
    assert files[1] == str(user_yaml)  # the user's file sits between the two inline dicts
    (first, first_values), (second, second_values) = proc.generated_parameter_files
    assert files == [first, str(user_yaml), second]
    assert first_values["message"] == "first" and second_values == {
        "rate": 3, "flag": True, "name": "Truex"}


def test_parameter_file_written_for_a_node_is_ros_yaml(tmp_path):
    from tuilaunch.engine.plan.params import write_parameter_file

    target = tmp_path / "p.yaml"
    write_parameter_file(target, {"rate": 2.0, "names": ["a", "b"]})
    assert yaml.safe_load(target.read_text()) == {
        "/**": {"ros__parameters": {"rate": 2.0, "names": ["a", "b"]}}}


def test_prefix_env_respawn_and_remapping_pairs(write):
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher()
    sl.node('tuilaunch_demos', 'listener', prefix='nice -n 5', additional_env={'A': 'b'},
            respawn=True, respawn_delay=1.5, remappings=[('chatter', 'other')])
    return sl.launch_description()
""")
    proc = plan_of(path).processes[0]
    assert proc.cmd[:3] == ["nice", "-n", "5"]
    assert proc.env == {"A": "b"} and not proc.clear_env
    assert proc.respawn and proc.respawn_delay == 1.5
    assert proc.respawn_max_retries == -1  # launch's default: no limit
    assert proc.remappings == [["chatter", "other"]]


def test_use_sim_time_is_forwarded_unless_the_node_sets_it(write):
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher(use_sim_time=False)
    sl.node('tuilaunch_demos', 'talker', name='plain')
    sl.node('tuilaunch_demos', 'talker', name='own', parameters={'use_sim_time': True})
    return sl.launch_description()
""")
    plain, own = plan_of(path, use_sim_time="true").processes
    assert plain.parameters == {"use_sim_time": True}
    assert own.parameters == {"use_sim_time": True}
    plain, own = plan_of(path).processes
    assert plain.parameters == {"use_sim_time": False} and own.parameters["use_sim_time"] is True
    assert [a.name for a in plan_of(path).arguments] == ["use_sim_time"]


def test_use_sim_time_auto_reads_the_live_graph(write, monkeypatch):
    monkeypatch.setenv("TUILAUNCH_SIM_TIME", "true")
    from tuilaunch.engine.describe.python.sim_clock import clock_is_published

    clock_is_published.cache_clear()
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher(use_sim_time='auto')
    assert sl.sim_time is True
    sl.node('tuilaunch_demos', 'talker')
    return sl.launch_description()
""")
    assert plan_of(path).processes[0].parameters == {"use_sim_time": True}
    clock_is_published.cache_clear()


def test_robot_state_publisher_runs_xacro_with_arguments(write):
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('prefix', 'bot')
    args = sl.arg_map('prefix')
    args['prefix'] += '/'
    args['x'] = 2.5
    sl.robot_state_publisher('tuilaunch_demos', 'turret.xacro', xacro_args=args,
                             remappings={'joint_states': 'js'})
    return sl.launch_description()
""")
    proc = plan_of(path, prefix="r9").processes[0]
    description = proc.parameters["robot_description"]
    assert isinstance(description, str)
    assert 'link name="r9/base_link"' in description and 'xyz="2.5 0 0"' in description
    # simple_launch hands launch_ros the output in single quotes, read as YAML: one string
    # whose line breaks are folded to spaces, as ros2 launch gives it to the node
    assert "\n" not in description and "<robot" in description
    assert proc.package == "robot_state_publisher" and proc.remappings == [["joint_states", "js"]]


def test_joint_state_publisher_and_rviz(write):
    path = write(HEADER + """
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('gui', False)
    sl.joint_state_publisher(use_gui=sl.arg('gui'), rate=10)
    sl.rviz('cfg.rviz')
    sl.rviz(warnings=True)
    return sl.launch_description()
""")
    jsp, gui, rviz, loud = plan_of(path).processes
    assert jsp.enabled and not gui.enabled and jsp.parameters == {"rate": 10}
    assert gui.package == "joint_state_publisher_gui"
    assert rviz.cmd[1:] == ["-d", "cfg.rviz", "--ros-args", "--log-level", "FATAL", "--ros-args"]
    assert loud.cmd[1:] == ["--ros-args"]
    assert {p.id for p in plan_of(path, gui="true").processes if p.enabled} == {
        gui.id, rviz.id, loud.id}
