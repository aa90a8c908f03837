"""XML launch files: every launch / launch_ros tag resolves as `ros2 launch` would run it."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tuilaunch.engine import ArgumentError, LaunchError
from tuilaunch.engine.errors import Origin
from tuilaunch.engine.plan.model import Plan, ProcessPlan

from ..conftest import EXAMPLES, plan_of, run_cli

LAUNCH = EXAMPLES / "launch"


def by_id(plan: Plan) -> dict[str, ProcessPlan]:
    return {p.id: p for p in plan.processes}


def ros_args(proc: ProcessPlan) -> list[str]:
    return proc.cmd[proc.cmd.index("--ros-args") + 1:] if "--ros-args" in proc.cmd else []


def logs(plan: Plan) -> list[str]:
    return [a.data for a in plan.actions if a.kind == "log" and a.enabled]


def xml(write, body: str, name: str = "test.launch.xml") -> Path:
    return write(f"<launch>\n{body}\n</launch>\n", name)


def test_ros2_demos_talker_listener_runs_the_two_demo_nodes():
    plan = plan_of(LAUNCH / "talker_listener.launch.xml")
    talker, listener = plan.processes
    assert (talker.package, talker.executable, talker.name, talker.namespace) == (
        "tuilaunch_demos", "talker", None, "/")
    assert (listener.package, listener.executable) == ("tuilaunch_demos", "listener")
    # no name, namespace or parameters given: the node's own code names it; launch_ros
    # still ends the command with an empty --ros-args block
    assert talker.cmd[0].endswith("lib/tuilaunch_demos/talker")
    assert talker.cmd[1:] == ["--ros-args"]
    assert talker.error is None and listener.error is None
    assert talker.origin is not None and talker.origin.line == 3


def test_arguments_defaults_descriptions_choices_and_form_types():
    plan = plan_of(LAUNCH / "bringup.launch.xml")
    args = {a.name: a for a in plan.arguments}
    assert list(args)[:4] == ["robot", "rate", "listener", "mode"]
    assert args["robot"].default == "r1"
    assert args["robot"].description == "robot name, used as the namespace of its nodes"
    assert args["mode"].choices == ["idle", "patrol", "dock"]
    assert (args["listener"].type, args["rate"].type, args["robot"].type) == (
        "bool", "float", "str")
    assert args["robot"].line == 6 and args["mode"].line == 9
    assert args["robot"].file == str(LAUNCH / "bringup.launch.xml")
    with pytest.raises(ArgumentError, match="'mode' = 'fly' is not one of its choices") as exc:
        plan_of(LAUNCH / "bringup.launch.xml", mode="fly")
    assert exc.value.origin is not None and exc.value.origin.line == 9


def test_show_args_and_json_give_xml_files_with_their_lines():
    shown = run_cli(str(LAUNCH / "bringup.launch.xml"), "--show-args")
    assert shown.returncode == 0, shown.stderr
    assert "robot" in shown.stdout and "robot name, used as the namespace" in shown.stdout
    assert "idle" in shown.stdout and "dock" in shown.stdout
    printed = run_cli(str(LAUNCH / "bringup.launch.xml"), "--print", "--json", "robot:=r4")
    assert printed.returncode == 0, printed.stderr
    import json

    data = json.loads(printed.stdout)
    talker = next(p for p in data["processes"] if p["executable"] == "talker")
    assert talker["namespace"] == "/r4"
    assert talker["parameters"] == {"rate": 2.0, "message": "r4 says hi"}
    assert talker["origin"].endswith("bringup.launch.xml:17")


def test_bringup_xml_means_what_the_same_python_file_means(write):
    python = write("""
import os
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, GroupAction, IncludeLaunchDescription
from launch.conditions import IfCondition, UnlessCondition
from launch.substitutions import LaunchConfiguration as V
from launch_ros.actions import Node, PushRosNamespace
from launch_ros.substitutions import FindPackageShare
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('robot', default_value='r1'),
        DeclareLaunchArgument('rate', default_value='2.0'),
        DeclareLaunchArgument('listener', default_value='true'),
        DeclareLaunchArgument('mode', default_value='patrol', choices=['idle', 'patrol', 'dock']),
        GroupAction([
            PushRosNamespace(V('robot')),
            Node(package='tuilaunch_demos', executable='talker',
                 parameters=[{'rate': V('rate'), 'message': [V('robot'), ' says hi']}]),
            Node(package='tuilaunch_demos', executable='listener',
                 condition=IfCondition(V('listener'))),
            GroupAction([PushRosNamespace('control'),
                         Node(package='tuilaunch_demos', executable='configurable',
                              parameters=[{'mode': V('mode')}])]),
            IncludeLaunchDescription([FindPackageShare('tuilaunch_demos'),
                                      '/launch/monitor.launch.py'],
                                     launch_arguments={'topic': 'chatter'}.items()),
            IncludeLaunchDescription(YAML, condition=UnlessCondition(V('listener'))),
        ]),
    ])
""".replace("YAML", repr(str(LAUNCH / "talker_listener.launch.yaml"))), "bringup_api.py")

    def summary(plan: Plan) -> list[tuple[object, ...]]:
        return [(p.package, p.executable, p.name, p.namespace, p.parameters, p.remappings,
                 p.enabled) for p in plan.processes if p.enabled]

    for values in ({}, {"robot": "r2", "listener": "false", "mode": "dock", "rate": "5"}):
        assert summary(plan_of(LAUNCH / "bringup.launch.xml", **values)) == summary(
            plan_of(python, **values))


def test_let_and_groups_scope_configurations_and_namespaces(write):
    path = xml(write, """
  <let name="who" value="outer"/>
  <group>
    <let name="who" value="inner"/>
    <push-ros-namespace namespace="a"/>
    <node pkg="tuilaunch_demos" exec="talker" name="t1">
      <param name="who" value="$(var who)"/>
    </node>
  </group>
  <node pkg="tuilaunch_demos" exec="talker" name="t2"><param name="who" value="$(var who)"/></node>
  <group scoped="false">
    <let name="who" value="leaked"/>
    <push_ros_namespace namespace="/abs"/>
    <node pkg="tuilaunch_demos" exec="talker" name="t3"/>
  </group>
  <node pkg="tuilaunch_demos" exec="talker" name="t4"><param name="who" value="$(var who)"/></node>
""")
    t1, t2, t3, t4 = plan_of(path).processes
    assert (t1.full_name, t1.parameters) == ("/a/t1", {"who": "inner"})
    assert (t2.full_name, t2.parameters) == ("/t2", {"who": "outer"})
    assert t3.full_name == "/abs/t3"
    assert t4.parameters == {"who": "leaked"}


def test_if_and_unless_work_on_every_action(write):
    path = xml(write, """
  <arg name="on" default="true"/>
  <let name="x" value="set" unless="$(var on)"/>
  <set_env name="FLAG" value="1" if="$(var on)"/>
  <group if="$(var on)"><node pkg="tuilaunch_demos" exec="talker" name="in_group"/></group>
  <node pkg="tuilaunch_demos" exec="talker" name="unless_on" unless="$(var on)"/>
  <executable cmd="true" name="exe" if="$(var on)"/>
  <timer period="1" unless="$(var on)"><log message="timed"/></timer>
  <log message="x is $(var x unset)" if="$(var on)"/>
  <include file="$(dirname)/child.launch.xml" unless="$(var on)"/>
""")
    xml(write, '<node pkg="tuilaunch_demos" exec="listener" name="child"/>', "child.launch.xml")
    on = plan_of(path)
    assert [(p.name, p.enabled) for p in on.processes] == [
        ("in_group", True), ("unless_on", False), ("exe", True), ("child", False)]
    assert on.process("exe-3").env == {"FLAG": "1"}
    assert logs(on) == ["x is unset"]
    off = plan_of(path, on="false")
    assert [(p.name, p.enabled) for p in off.processes] == [
        ("in_group", False), ("unless_on", True), ("exe", False), ("child", True)]
    assert [a.enabled for a in off.actions if a.kind == "log"] == [True, False]
    assert off.process("unless_on-2").env == {}


def test_node_attributes_map_onto_the_command_line(write):
    path = xml(write, """
  <arg name="robot" default="r2"/>
  <node pkg="tuilaunch_demos" exec="talker" name="talk_$(var robot)" namespace="ns1"
        args="--one $(var robot)_x 'two words' --three=$(var robot)" output="screen"
        respawn="true" respawn_delay="2.5" respawn_max_retries="3"
        launch-prefix="nice -n 5" ros_args="--log-level debug">
    <remap from="chatter" to="/$(var robot)/chatter"/>
    <env name="MY_VAR" value="$(var robot)"/>
  </node>
  <node pkg="tuilaunch_demos" exec="listener" namespace="/other" exec_name="lis"/>
""")
    talker, listener = plan_of(path).processes
    assert talker.full_name == "/ns1/talk_r2"
    assert talker.cmd[:3] == ["nice", "-n", "5"]
    assert talker.cmd[3].endswith("lib/tuilaunch_demos/talker")
    assert talker.cmd[4:9] == ["--one", "r2_x", "two words", "--three=r2", "--ros-args"]
    assert ros_args(talker) == ["--log-level", "debug", "--ros-args", "-r", "__node:=talk_r2",
                                "-r", "__ns:=/ns1", "-r", "chatter:=/r2/chatter"]
    assert talker.env == {"MY_VAR": "r2"} and not talker.clear_env
    assert (talker.respawn, talker.respawn_delay, talker.respawn_max_retries) == (True, 2.5, 3)
    assert listener.namespace == "/other" and listener.name is None


def test_parameters_values_types_nesting_and_files(write, tmp_path):
    params_file = tmp_path / "extra.yaml"
    params_file.write_text("/**:\n  ros__parameters:\n    from_file: 1\n")
    path = xml(write, f"""
  <arg name="n" default="7"/>
  <node pkg="tuilaunch_demos" exec="talker" name="p">
    <param name="an_int" value="1"/>
    <param name="a_float" value="1.5"/>
    <param name="a_bool" value="true"/>
    <param name="a_list" value="[1, 2]"/>
    <param name="words" value="[a, b]"/>
    <param name="text" value="hello world"/>
    <param name="quoted" value="'1'"/>
    <param name="forced_str" value="1" type="str"/>
    <param name="forced_float" value="2" type="float"/>
    <param name="forced_bool" value="1" type="bool"/>
    <param name="from_arg" value="$(var n)"/>
    <param name="from_arg_str" value="$(var n)" type="str"/>
    <param name="from_arg_float" value="$(var n)" type="float"/>
    <param name="sep_list" value="1,2,3" value-sep=","/>
    <param name="sep_words" value="$(var n);8" value-sep=";"/>
    <param name="typed_list" value="[1, 2]" type="list_of_float"/>
    <param name="outer">
      <param name="inner" value="3"/>
      <param name="deeper"><param name="leaf" value="x"/></param>
    </param>
    <param from="{params_file}"/>
    <param name="after_file" value="2"/>
  </node>
""")
    proc = plan_of(path).processes[0]
    assert proc.parameters == {
        "an_int": 1, "a_float": 1.5, "a_bool": True, "a_list": [1, 2], "words": ["a", "b"],
        "text": "hello world", "quoted": "1", "forced_str": "1", "forced_float": 2.0,
        "forced_bool": True, "from_arg": 7, "from_arg_str": "7", "from_arg_float": 7.0,
        "sep_list": [1, 2, 3], "sep_words": [7, 8], "typed_list": [1.0, 2.0],
        "outer.inner": 3, "outer.deeper.leaf": "x", "after_file": 2}
    assert isinstance(proc.parameters["forced_float"], float)
    # as launch_ros: each <param name=> is a file of its own, and the `from=` file keeps its
    # place between them
    files = [a for i, a in enumerate(ros_args(proc)) if ros_args(proc)[i - 1] == "--params-file"]
    assert len(files) == 19 and files[17] == str(params_file)
    assert proc.parameter_files == [str(params_file)]


def test_parameter_type_that_does_not_fit_names_the_parameter(write):
    path = xml(write, """
  <arg name="n" default="seven"/>
  <node pkg="tuilaunch_demos" exec="talker"><param name="count" value="$(var n)" type="int"/></node>
""")
    with pytest.raises(Exception, match="parameter 'count' = 'seven' is not an integer"):
        plan_of(path)
    assert plan_of(path, n="8").processes[0].parameters == {"count": 8}


def test_executable_cmd_cwd_name_shell_env(write, tmp_path):
    path = xml(write, f"""
  <arg name="who" default="world"/>
  <executable cmd="echo hello $(var who)" cwd="{tmp_path}" name="greeter">
    <env name="GREETING" value="hi"/>
  </executable>
  <executable cmd="echo $HOME | tr a-z A-Z" shell="true" name="piped"/>
""")
    greeter, piped = plan_of(path).processes
    assert greeter.cmd == ["echo", "hello", "world"]
    assert (greeter.name, greeter.cwd, greeter.env) == ("greeter", str(tmp_path),
                                                        {"GREETING": "hi"})
    assert piped.cmd == ["/bin/sh", "-c", "echo $HOME | tr a-z A-Z"]


def test_environment_actions_apply_to_what_follows_in_their_scope(write):
    os.environ["TUILAUNCH_TEST_UNSET_ME"] = "x"
    try:
        path = xml(write, """
  <set_env name="A" value="1"/>
  <group>
    <set_env name="B" value="2"/>
    <unset_env name="A"/>
    <executable cmd="true" name="inner"/>
  </group>
  <executable cmd="true" name="outer"/>
  <append_env name="TUILAUNCH_TEST_UNSET_ME" value="y"/>
  <executable cmd="true" name="appended"/>
""")
        inner, outer, appended = plan_of(path).processes
    finally:
        del os.environ["TUILAUNCH_TEST_UNSET_ME"]
    assert inner.env == {"B": "2"}
    assert outer.env == {"A": "1"}
    assert appended.env["TUILAUNCH_TEST_UNSET_ME"] == "x" + os.pathsep + "y"


def test_set_parameter_set_remap_and_use_sim_time_reach_later_nodes_only(write):
    path = xml(write, """
  <node pkg="tuilaunch_demos" exec="talker" name="before"/>
  <group>
    <set_parameter name="use_fast" value="true"/>
    <set_parameter name="rate" value="3"/>
    <set_remap from="chatter" to="/shared"/>
    <set_use_sim_time value="true"/>
    <node pkg="tuilaunch_demos" exec="talker" name="inside"/>
  </group>
  <node pkg="tuilaunch_demos" exec="talker" name="after"/>
""")
    before, inside, after = plan_of(path).processes
    assert inside.parameters == {"use_fast": True, "rate": 3, "use_sim_time": True}
    assert inside.remappings == [["chatter", "/shared"]]
    assert before.parameters == {} == after.parameters and after.remappings == []


def test_timer_delays_its_actions_and_log_prints(write):
    path = xml(write, """
  <arg name="delay" default="2.5"/>
  <log message="now"/>
  <timer period="$(var delay)">
    <node pkg="tuilaunch_demos" exec="talker" name="late"/>
    <log message="later"/>
  </timer>
""")
    plan = plan_of(path)
    late = plan.processes[0]
    assert late.trigger is not None and (late.trigger.on, late.trigger.delay) == ("timer", 2.5)
    assert logs(plan) == ["now", "later"]
    assert plan.actions[0].trigger is None and plan.actions[1].trigger is not None


def test_containers_and_composable_nodes(write):
    path = xml(write, """
  <node_container pkg="rclcpp_components" exec="component_container" name="box" namespace="ns">
    <composable_node pkg="composition" plugin="composition::Talker" name="talker">
      <param name="rate" value="2"/>
      <remap from="chatter" to="out"/>
    </composable_node>
  </node_container>
  <load_composable_node target="/ns/box">
    <composable_node pkg="composition" plugin="composition::Listener" name="listener"
                     namespace="sub"/>
    <composable_lifecycle_node pkg="composition" plugin="composition::Server" name="server"
                               autostart="true"/>
  </load_composable_node>
""")
    plan = plan_of(path)
    box = plan.processes[0]
    assert (box.kind, box.full_name, box.package) == ("container", "/ns/box",
                                                      "rclcpp_components")
    # a component takes the pushed namespace, not its container's (launch_ros does so)
    (talker,) = box.components
    assert {k: talker[k] for k in ("package", "plugin", "name", "namespace", "parameters",
                                   "remappings")} == {
        "package": "composition", "plugin": "composition::Talker", "name": "talker",
        "namespace": "/", "parameters": {"rate": 2}, "remappings": [["chatter", "out"]]}
    load = next(a for a in plan.actions if a.kind == "load_components")
    assert load.target == "/ns/box"
    assert [(c["plugin"], c["namespace"]) for c in load.data] == [
        ("composition::Listener", "/sub"), ("composition::Server", "/")]


def test_lifecycle_node_is_a_process_with_its_name_namespace_and_parameters(write):
    path = xml(write, """
  <lifecycle_node pkg="tuilaunch_demos" exec="configurable" name="life" namespace="lc"
                  autostart="true">
    <param name="mode" value="idle"/>
  </lifecycle_node>
""")
    proc = plan_of(path).processes[0]
    assert (proc.full_name, proc.parameters) == ("/lc/life", {"mode": "idle"})
    assert "__node:=life" in ros_args(proc)


def test_include_passes_arguments_to_python_and_python_includes_xml(write):
    path = xml(write, """
  <include file="$(find-pkg-share tuilaunch_demos)/launch/monitor.launch.py">
    <arg name="topic" value="/from_xml"/>
  </include>
""")
    monitor = plan_of(path).processes[0]
    assert (monitor.full_name, monitor.remappings) == ("/monitor", [["chatter", "/from_xml"]])
    plan = plan_of(LAUNCH / "includes_xml.launch.py")
    names = [(p.full_name or p.label, p.enabled) for p in plan.processes]
    assert names[0] == ("/from_python/<talker>", True)
    assert ("/from_python/<listener>", False) in names  # listener:=false passed by Python
    assert plan.process("monitor-4").full_name == "/from_python/monitor"


def test_python_includes_xml_and_yaml_through_their_source_classes(write):
    xml(write, '<arg name="who" default="x"/>\n<node pkg="tuilaunch_demos" exec="talker" '
               'name="$(var who)"/>', "child.launch.xml")
    write("launch:\n- node: {pkg: tuilaunch_demos, exec: listener, name: from_yaml}\n",
          "child.launch.yaml")
    path = write("""
import os
from launch import LaunchDescription
from launch.actions import IncludeLaunchDescription
from launch.launch_description_sources import FrontendLaunchDescriptionSource
from launch_xml.launch_description_sources import XMLLaunchDescriptionSource
from launch_yaml.launch_description_sources import YAMLLaunchDescriptionSource
here = os.path.dirname(__file__)
def generate_launch_description():
    return LaunchDescription([
        IncludeLaunchDescription(XMLLaunchDescriptionSource(os.path.join(here, 'child.launch.xml')),
                                 launch_arguments=[('who', 'from_xml')]),
        IncludeLaunchDescription(
            YAMLLaunchDescriptionSource(os.path.join(here, 'child.launch.yaml'))),
        IncludeLaunchDescription(
            FrontendLaunchDescriptionSource(os.path.join(here, 'child.launch.xml'))),
    ])
""", "parent.launch.py")
    assert [p.full_name for p in plan_of(path).processes] == [
        "/from_xml", "/from_yaml", "/from_xml"]  # the argument stays set, as in launch


def test_on_exit_shutdown_and_unsupported_actions_are_reported(write):
    path = xml(write, """
  <executable cmd="true" name="once" on_exit="shutdown"/>
  <set_ros_log_dir new_log_dir="/tmp/elsewhere"/>
""")
    plan = plan_of(path)
    handler = next(item for item in plan.tree.children if item.label == "on exit")
    assert handler.trigger is not None and handler.trigger.target == "once-1"
    assert any(a.kind == "shutdown" for a in plan.actions)
    assert any("<set_ros_log_dir>" in w and "test.launch.xml:4" in w for w in plan.warnings)


def test_the_readme_xml_example_reads_into_the_entities_it_shows(write):
    from tuilaunch.engine import load_file
    from tuilaunch.engine.describe import entities

    readme = (EXAMPLES.parent / "docs" / "launch-files.md").read_text()
    block = readme.split("```xml\n", 1)[1].split("```", 1)[0]
    loaded = load_file(str(write(block, "readme.launch.xml")))
    kinds = [type(e) for e in loaded.entities]
    assert kinds == [entities.DeclareLaunchArgument, entities.DeclareLaunchArgument,
                     entities.SetLaunchConfiguration, entities.Group,
                     entities.IncludeLaunchDescription]
    group = loaded.entities[3]
    assert [type(e).__name__ for e in group.children] == ["PushRosNamespace", "Node", "Node",
                                                          "Node", "Node"]
    assert group.children[4].condition is not None


def test_parameter_files_with_allow_substs_get_their_substitutions_performed(write, tmp_path):
    source = tmp_path / "subst.yaml"
    source.write_text("/**:\n  ros__parameters:\n    robot: $(var robot)\n"
                      "    shell: $(env SHELL_FOR_TEST sh)\n")
    path = xml(write, f"""
  <arg name="robot" default="r5"/>
  <node pkg="tuilaunch_demos" exec="talker">
    <param from="{source}" allow_substs="true"/>
    <param from="{source}"/>
  </node>
""")
    substituted, untouched = plan_of(path, robot="r6").processes[0].parameter_files
    assert untouched == str(source)
    assert Path(substituted).read_text() == (
        "/**:\n  ros__parameters:\n    robot: r6\n    shell: sh\n")
    source.write_text("/**:\n  ros__parameters:\n    robot: $(var robot\n")
    with pytest.raises(LaunchError, match=r"is not closed") as exc:
        plan_of(path)
    assert exc.value.origin == Origin(str(source), 3, 12)  # the `$(` in the YAML file


def test_group_without_forwarding_sees_only_what_it_keeps(write):
    path = xml(write, """
  <let name="foo" value="FOO"/>
  <let name="bar" value="BAR"/>
  <set_env name="OUTER" value="1"/>
  <group scoped="True" forwarding="False">
    <keep name="bar" value="$(var bar)"/>
    <keep name="baz" value="BAZ"/>
    <log message="$(var foo gone) $(var bar) $(var baz)"/>
    <executable cmd="true" name="inside"/>
  </group>
  <group>
    <keep name="baz" value="kept"/>
    <log message="$(var foo) $(var baz)"/>
  </group>
  <log message="$(var foo) $(var baz unset)"/>
""")
    plan = plan_of(path)
    assert logs(plan) == ["gone BAR BAZ", "FOO kept", "FOO unset"]
    assert plan.processes[0].env == {}  # the environment is reset too


def test_a_deprecated_launch_file_says_so(write):
    path = write('<launch deprecated="use new.launch.xml">\n'
                 '  <node pkg="tuilaunch_demos" exec="talker"/>\n</launch>', "old.launch.xml")
    assert logs(plan_of(path)) == ["old.launch.xml is deprecated: use new.launch.xml"]


def test_xml_includes_an_opaque_function_file_and_simple_launch_includes_xml(write):
    write("""
from simple_launch import SimpleLauncher
sl = SimpleLauncher()
sl.declare_arg('copies', 1)
def setup():
    for i in range(sl.arg('copies')):
        sl.node('tuilaunch_demos', 'talker', name=f'copy{i}')
    return sl.launch_description()
generate_launch_description = sl.launch_description(opaque_function=setup)
""", "opaque.launch.py")
    parent = xml(write, """
  <arg name="n" default="2"/>
  <group>
    <push-ros-namespace namespace="fleet"/>
    <include file="$(dirname)/opaque.launch.py"><arg name="copies" value="$(var n)"/></include>
  </group>
""", "parent.launch.xml")
    assert [p.full_name for p in plan_of(parent, n="3").processes] == [
        "/fleet/copy0", "/fleet/copy1", "/fleet/copy2"]
    python = write("""
import os
from simple_launch import SimpleLauncher
def generate_launch_description():
    sl = SimpleLauncher(namespace='top')
    sl.include(None, os.path.join(os.path.dirname(__file__), 'parent.launch.xml'),
               launch_arguments={'n': 1})
    return sl.launch_description()
""", "top.launch.py")
    assert [p.full_name for p in plan_of(python).processes] == ["/top/fleet/copy0"]


def test_reset_and_reset_env_forget_what_came_before(write):
    path = xml(write, """
  <let name="a" value="A"/>
  <let name="b" value="B"/>
  <set_env name="E" value="1"/>
  <executable cmd="true" name="before"/>
  <group>
    <reset><keep name="b" value="$(var b)"/></reset>
    <reset_env/>
    <log message="$(var a gone) $(var b)"/>
    <executable cmd="true" name="after"/>
  </group>
  <log message="$(var a)"/>
""")
    plan = plan_of(path)
    assert logs(plan) == ["gone B", "A"]  # the group's scope ends the reset
    assert [p.env for p in plan.processes] == [{"E": "1"}, {}]


def test_set_parameters_from_file_reaches_the_nodes_that_follow_in_scope(write, tmp_path):
    shared = tmp_path / "shared.yaml"
    shared.write_text("/**:\n  ros__parameters:\n    shared: 1\n")
    path = xml(write, f"""
  <group>
    <set_parameter name="first" value="1"/>
    <set_parameters_from_file filename="{shared}"/>
    <node pkg="tuilaunch_demos" exec="talker" name="inside">
      <param name="own" value="2"/>
    </node>
  </group>
  <node pkg="tuilaunch_demos" exec="talker" name="outside"/>
""")
    inside, outside = plan_of(path).processes
    args = ros_args(inside)
    files = [a for i, a in enumerate(args) if args[i - 1] == "--params-file"]
    # launch_ros's order: the scope's parameters (values as -p, then the file), then the
    # node's own
    assert args[args.index("-p"):args.index("-p") + 2] == ["-p", "first:=1"]
    assert args.index("-p") < args.index(str(shared))
    assert len(files) == 2 and files[0] == str(shared)
    assert inside.generated_parameter_files[0][1] == {"own": 2}
    assert inside.parameters == {"first": 1, "own": 2}  # the file's values stay in the file
    assert inside.parameter_files == [str(shared)] and outside.parameter_files == []
