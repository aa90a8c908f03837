"""What reaches each process as `ros2 launch` (launch 3.x, launch_ros Jazzy) would give it.

Each launch file here is written for the test, in the pattern real bringups use (nav2's
`PushROSNamespace(namespace)` with an empty default, the ros2 demos' containers with
`namespace=''`, ...); the expectations are what launch_ros puts on the command line.
"""

from __future__ import annotations

import itertools

from ..conftest import plan_of, run_cli

PY = """\
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, GroupAction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node, PushROSNamespace
from launch_ros.substitutions import FindPackageShare
"""


def ros_part(cmd: list[str]) -> list[str]:
    return cmd[cmd.index("--ros-args"):]


def test_every_node_command_ends_with_a_ros_args_block(write):
    path = write(PY + """
def generate_launch_description():
    return LaunchDescription([
        Node(package='tuilaunch_demos', executable='talker'),
        Node(package='tuilaunch_demos', executable='talker', arguments=['one', 'two'],
             ros_arguments=['--log-level', 'debug'], name='t'),
        ExecuteProcess(cmd=['true', 'x']),
    ])
""")
    bare, with_args, process = plan_of(path).processes
    # launch_ros always appends --ros-args, even with nothing after it
    assert bare.cmd[1:] == ["--ros-args"]
    # the user's ros_arguments get a block of their own, before launch_ros's
    assert with_args.cmd[1:] == ["one", "two", "--ros-args", "--log-level", "debug",
                                 "--ros-args", "-r", "__node:=t"]
    # a plain process gets nothing added
    assert process.cmd == ["true", "x"]


def test_a_namespace_pushed_or_given_empty_is_passed_as_root(write):
    path = write(PY + """
def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('namespace', default_value=''),
        Node(package='tuilaunch_demos', executable='talker', name='given_empty', namespace=''),
        Node(package='tuilaunch_demos', executable='talker', name='not_given'),
        GroupAction([
            PushROSNamespace(LaunchConfiguration('namespace')),
            Node(package='tuilaunch_demos', executable='talker', name='pushed_empty'),
        ]),
        GroupAction([
            PushROSNamespace('r1'),
            Node(package='tuilaunch_demos', executable='talker', name='pushed',
                 namespace='sub'),
        ]),
    ])
""")
    by_name = {p.name: p for p in plan_of(path).processes}
    assert ros_part(by_name["given_empty"].cmd) == ["--ros-args", "-r", "__node:=given_empty",
                                                    "-r", "__ns:=/"]
    assert ros_part(by_name["not_given"].cmd) == ["--ros-args", "-r", "__node:=not_given"]
    assert ros_part(by_name["pushed_empty"].cmd) == ["--ros-args", "-r",
                                                     "__node:=pushed_empty", "-r", "__ns:=/"]
    assert ros_part(by_name["pushed"].cmd) == ["--ros-args", "-r", "__node:=pushed", "-r",
                                               "__ns:=/r1/sub"]
    assert by_name["pushed"].full_name == "/r1/sub/pushed"


def test_find_package_share_find_works_while_the_file_loads(write):
    path = write(PY + """
import os

def generate_launch_description():
    share = FindPackageShare('tuilaunch_demos').find('tuilaunch_demos')
    assert os.path.isdir(share), share
    return LaunchDescription([
        ExecuteProcess(cmd=['ls', os.path.join(share, 'package.xml')]),
    ])
""")
    (process,) = plan_of(path).processes
    assert process.cmd[1].endswith("share/tuilaunch_demos/package.xml")


def test_a_push_ros_namespace_whose_condition_is_false_pushes_nothing(write):
    # nav2's bringup: PushROSNamespace(condition=IfCondition(use_namespace), namespace=...)
    path = write(PY + """
from launch.conditions import IfCondition

def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('namespace', default_value='robot1'),
        DeclareLaunchArgument('use_namespace', default_value='false'),
        GroupAction([
            PushROSNamespace(condition=IfCondition(LaunchConfiguration('use_namespace')),
                             namespace=LaunchConfiguration('namespace')),
            Node(package='tuilaunch_demos', executable='talker', name='amcl'),
        ]),
    ])
""")
    (off,) = plan_of(path).processes
    assert off.full_name == "/amcl" and ros_part(off.cmd) == ["--ros-args", "-r", "__node:=amcl"]
    (on,) = plan_of(path, use_namespace="true").processes
    assert on.full_name == "/robot1/amcl"
    assert ros_part(on.cmd) == ["--ros-args", "-r", "__node:=amcl", "-r", "__ns:=/robot1"]


def test_parameters_reach_the_command_line_in_launch_ros_order(write, tmp_path):
    shared = tmp_path / "shared.yaml"
    shared.write_text("/**:\n  ros__parameters:\n    from_file: 1\n")
    path = write(PY + f"""
from launch_ros.actions import SetParameter, SetParametersFromFile
from launch_ros.descriptions import ParameterValue
from launch_ros.parameter_descriptions import Parameter

def generate_launch_description():
    return LaunchDescription([
        SetParameter(name='use_sim_time', value=True),
        SetParametersFromFile('{shared}'),
        Node(package='tuilaunch_demos', executable='talker', name='t', parameters=[
            {{'a': 1}}, {{'b': 'x'}}, '{shared}',
            Parameter('c', ParameterValue('true', value_type=str))]),
    ])
""")
    (proc,) = plan_of(path).processes
    ros = ros_part(proc.cmd)
    # SetParameter as -p (Python's text of the value), SetParametersFromFile, then each dict
    # in a file of its own, the file where it stands, a Parameter as -p with YAML text
    assert ros[:5] == ["--ros-args", "-r", "__node:=t", "-p", "use_sim_time:=True"]
    kinds = [(a, b) for a, b in itertools.pairwise(ros) if a in ("-p", "--params-file")]
    assert [k for k, _ in kinds] == ["-p", "--params-file", "--params-file", "--params-file",
                                     "--params-file", "-p"]
    assert kinds[1][1] == str(shared) and kinds[4][1] == str(shared)
    assert [values for _, values in proc.generated_parameter_files] == [{"a": 1}, {"b": "x"}]
    assert [path for path, _ in proc.generated_parameter_files] == [kinds[2][1], kinds[3][1]]
    assert kinds[5][1].startswith("c:='true'")  # stays text for rcl
    assert proc.parameters == {"use_sim_time": True, "a": 1, "b": "x", "c": "true"}


def test_a_parameter_file_that_is_not_there_is_a_warning_and_the_node_starts(write, tmp_path):
    path = write(PY + f"""
def generate_launch_description():
    return LaunchDescription([
        Node(package='tuilaunch_demos', executable='talker', name='t',
             parameters=['{tmp_path}/missing.yaml', {{'a': 1}}]),
    ])
""")
    plan = plan_of(path)
    (proc,) = plan.processes
    assert proc.error is None and str(tmp_path / "missing.yaml") not in proc.cmd
    assert proc.parameter_files == [] and proc.parameters == {"a": 1}
    assert any("missing.yaml is not a file: t starts without it" in w and "test_launch.py:9" in w
               for w in plan.warnings), plan.warnings


def test_simple_launch_joint_state_publisher_without_keywords_gets_an_empty_file(write):
    path = write("""
from simple_launch import SimpleLauncher

def generate_launch_description():
    sl = SimpleLauncher()
    with sl.group(ns='r5'):
        sl.joint_state_publisher(use_gui=False)
    return sl.launch_description()
""")
    jsp = next(p for p in plan_of(path).processes if p.enabled)
    # simple_launch gives Node(parameters={}) and launch_ros writes it as a file of its own
    assert ros_part(jsp.cmd)[:4] == ["--ros-args", "-r", "__ns:=/r5", "--params-file"]
    assert [values for _, values in jsp.generated_parameter_files] == [{}]


def test_simple_launch_container_has_the_empty_namespace_simple_launch_gives_it(write):
    path = write("""
from simple_launch import SimpleLauncher

def generate_launch_description():
    sl = SimpleLauncher()
    with sl.container(name='my_container'):
        sl.node(package='tuilaunch_demos', plugin='Talker', name='talker')
    return sl.launch_description()
""")
    (container,) = plan_of(path).processes
    # simple_launch: ComposableNodeContainer(namespace='') -> launch_ros passes __ns:=/
    assert ros_part(container.cmd) == ["--ros-args", "-r", "__node:=my_container", "-r",
                                       "__ns:=/"]
    assert [c["request"]["node_name"] for c in container.components] == ["talker"]


SCOPES = PY + """
from launch.actions import SetEnvironmentVariable, SetLaunchConfiguration
from launch_ros.actions import SetParameter, SetRemap

def generate_launch_description():
    return LaunchDescription([
        SetRemap(src='/tf', dst='tf'),
        GroupAction(scoped=False, actions=[
            PushROSNamespace('r1'),
            SetParameter(name='use_sim_time', value=True),
            SetEnvironmentVariable('FROM_UNSCOPED', 'yes'),
        ]),
        Node(package='tuilaunch_demos', executable='talker', name='after_unscoped'),
        GroupAction([
            PushROSNamespace('inner'),
            SetRemap(src='chatter', dst='chat'),
            SetParameter(name='inner_param', value=1),
            SetEnvironmentVariable('FROM_SCOPED', 'yes'),
            Node(package='tuilaunch_demos', executable='talker', name='inside'),
        ]),
        Node(package='tuilaunch_demos', executable='talker', name='after_scoped'),
        GroupAction(forwarding=False, launch_configurations={'kept': 'k'}, actions=[
            Node(package='tuilaunch_demos', executable='talker', name='reset'),
        ]),
    ])
"""


def test_group_scopes_as_launch_has_them(write):
    by_name = {p.name: p for p in plan_of(write(SCOPES)).processes}
    # an unscoped group's namespace, SetParameter and environment stay after it
    after = by_name["after_unscoped"]
    assert after.full_name == "/r1/after_unscoped"
    assert after.parameters == {"use_sim_time": True} and after.env == {"FROM_UNSCOPED": "yes"}
    assert ros_part(after.cmd) == ["--ros-args", "-r", "__node:=after_unscoped", "-r",
                                   "__ns:=/r1", "-p", "use_sim_time:=True", "-r", "/tf:=tf"]
    # a scoped group's namespace and environment end with it; launch_ros appends its
    # SetParameter and SetRemap to the lists the launch already holds, so those stay
    # (ros2 launch gives after_scoped chatter:=chat and inner_param too)
    inside, later = by_name["inside"], by_name["after_scoped"]
    assert inside.full_name == "/r1/inner/inside" and later.full_name == "/r1/after_scoped"
    assert later.env == {"FROM_UNSCOPED": "yes"}
    assert later.remappings == [["/tf", "tf"], ["chatter", "chat"]]
    assert later.parameters == {"use_sim_time": True, "inner_param": 1}
    # forwarding=False: nothing pushed before reaches the group
    reset = by_name["reset"]
    assert reset.full_name == "/reset" and reset.parameters == {} and reset.remappings == []
    assert ros_part(reset.cmd) == ["--ros-args", "-r", "__node:=reset"]


def test_what_an_included_file_pushes_stays_pushed_after_it(write, tmp_path):
    (tmp_path / "child.launch.py").write_text(PY + """
from launch_ros.actions import SetRemap

def generate_launch_description():
    return LaunchDescription([PushROSNamespace('from_child'), SetRemap(src='a', dst='b')])
""")
    path = write(PY + """
from launch.actions import IncludeLaunchDescription
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import ThisLaunchFileDir

def generate_launch_description():
    return LaunchDescription([
        IncludeLaunchDescription(PythonLaunchDescriptionSource(
            [ThisLaunchFileDir(), '/child.launch.py'])),
        Node(package='tuilaunch_demos', executable='talker', name='after'),
    ])
""")
    (after,) = plan_of(path).processes
    assert after.full_name == "/from_child/after" and after.remappings == [["a", "b"]]


def test_xml_extra_arg_values_are_read_as_yaml(write):
    path = write("""<launch>
  <node_container pkg="tuilaunch_demos" exec="component_container" name="box" namespace="">
    <composable_node pkg="tuilaunch_demos" plugin="tuilaunch_demos::Talker" name="t">
      <extra_arg name="use_intra_process_comms" value="true"/>
    </composable_node>
  </node_container>
</launch>
""", name="box.launch.xml")
    (component,) = plan_of(path).processes[0].components
    assert component["extra_arguments"] == {"use_intra_process_comms": True}


def test_node_keywords_launch_ros_passes_to_execute_process(write):
    # controller_manager's launch helpers: Node(..., shell=True) runs through /bin/sh
    path = write(PY + """
def generate_launch_description():
    return LaunchDescription([
        Node(package='tuilaunch_demos', executable='talker', arguments=['a', 'b c'],
             shell=True, output_format='[{this.process_description.final_name}] {line}',
             cached_output=False),
    ])
""")
    (proc,) = plan_of(path).processes
    assert proc.cmd[:2] == ["/bin/sh", "-c"] and len(proc.cmd) == 3
    assert proc.cmd[2].endswith("lib/tuilaunch_demos/talker a b c --ros-args")


def test_show_args_lists_arguments_that_have_no_value_yet(write):
    # ros2 launch --show-args needs no values: ros_gz_sim's and autoware's files declare
    # arguments without defaults and include files named by them
    path = write("""<launch>
  <arg name="world" description="the world to load"/>
  <arg name="mode" default="a"><choice value="a"/><choice value="b"/></arg>
  <include file="$(var world)/missing.launch.xml"/>
  <arg name="after" default="x" description="declared after the include"/>
</launch>
""", name="needs.launch.xml")
    result = run_cli(str(path), "--show-args")
    assert result.returncode == 0, result.stderr
    out = result.stdout
    assert "'world':" in out and "the world to load" in out and "(required)" in out
    # DeclareLaunchArgument's description of choices without a description of its own
    assert "    'mode':\n        One of: ['a', 'b']\n        (default: 'a')\n" in out
    assert "'mode':" in out and "'after':" in out and "declared after the include" in out
    assert "some arguments may be missing" in result.stderr and "missing.launch.xml" in \
        result.stderr
    # launching still needs the value
    assert run_cli(str(path), "--print").returncode == 2


def test_simple_launch_parameters_and_use_sim_time_reach_one_file_as_simple_launch_builds_it(
        write, tmp_path):
    yaml_with = tmp_path / "with.yaml"
    yaml_with.write_text("/**:\n  ros__parameters:\n    use_sim_time: false\n")
    yaml_without = tmp_path / "without.yaml"
    yaml_without.write_text("/**:\n  ros__parameters:\n    rate: 2\n")
    path = write(f"""
from simple_launch import SimpleLauncher

def generate_launch_description():
    sl = SimpleLauncher(use_sim_time=True)
    sl.node('tuilaunch_demos', 'talker', name='dicts', parameters=[{{'a': 1}}, {{'b': 2}}])
    sl.node('tuilaunch_demos', 'talker', name='own', parameters={{'use_sim_time': False}})
    sl.node('tuilaunch_demos', 'talker', name='file_with', parameters=['{yaml_with}'])
    sl.node('tuilaunch_demos', 'talker', name='file_without', parameters=['{yaml_without}'])
    sl.node('tuilaunch_demos', 'talker', name='none')
    return sl.launch_description()
""")
    by_name = {p.name: p for p in plan_of(path).processes}

    def files(name: str) -> list[dict]:
        return [values for _, values in by_name[name].generated_parameter_files]

    # simple_launch merges a list of dicts into one, and adds use_sim_time into the first
    assert files("dicts") == [{"a": 1, "b": 2, "use_sim_time": True}]
    assert files("own") == [{"use_sim_time": False}]
    # after a first YAML file: only when the file does not set it
    assert files("file_with") == [] and by_name["file_with"].parameter_files == [str(yaml_with)]
    assert files("file_without") == [{"use_sim_time": True}]
    assert files("none") == [{"use_sim_time": True}]


def test_show_args_of_a_file_without_arguments_says_so_as_ros2_launch(write):
    path = write("<launch>\n  <executable cmd=\"true\"/>\n</launch>\n", name="none.launch.xml")
    result = run_cli(str(path), "--show-args")
    assert result.returncode == 0, result.stderr
    assert result.stdout == "Arguments (pass arguments as '<name>:=<value>'):\n\n" \
        "  No arguments.\n"


def test_a_process_gets_pipes_unless_emulate_tty_and_the_configuration_overrides_it(write):
    """launch: ExecuteLocal's `emulate_tty: bool = False`, and `if 'emulate_tty' in
    context.launch_configurations`, it decides for every process, whatever the process's own
    emulate_tty says."""
    path = write("""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    probe = 'if [ -t 1 ]; then echo terminal; else echo pipe; fi'
    return LaunchDescription([
        ExecuteProcess(cmd=['sh', '-c', probe], name='asks', output='screen',
                       emulate_tty=True),
        ExecuteProcess(cmd=['sh', '-c', probe], name='plain', output='screen'),
    ])
""")
    shown = run_cli(str(path), "--headless")
    assert "[asks-1] terminal" in shown.stdout and "[plain-2] pipe" in shown.stdout, \
        shown.stdout
    every = run_cli(str(path), "--headless", "emulate_tty:=true")
    assert "[asks-1] terminal" in every.stdout and "[plain-2] terminal" in every.stdout, \
        every.stdout
    piped = run_cli(str(path), "--headless", "emulate_tty:=false")
    assert "[asks-1] pipe" in piped.stdout and "[plain-2] pipe" in piped.stdout, piped.stdout
    assert "not declared" not in piped.stderr
