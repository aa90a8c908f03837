"""`launch` / `launch_ros` as packages with launch's module tree, and the context API that
third-party extensions (Substitution and Action subclasses) rely on."""

from __future__ import annotations

import importlib
import json
import sys
from pathlib import Path

import pytest
import yaml

from tuilaunch.engine.describe.python.compat import NAMES, UNSUPPORTED
from tuilaunch.engine.describe.python.loader import compat_modules, load_file
from tuilaunch.engine.errors import LaunchError

from ..conftest import plan_of, run_cli
from .launch_world import install_extension, make_package, world_env

# Where real launch files and extensions import these from (launch 3.x, launch_ros Jazzy).
REAL_IMPORTS = [
    ("launch", "LaunchDescription"), ("launch", "SomeSubstitutionsType"),
    ("launch", "LaunchContext"), ("launch", "Substitution"), ("launch", "Action"),
    ("launch.launch_description", "LaunchDescription"),
    ("launch.substitutions.command", "Command"),
    ("launch.substitutions", "PathSubstitution"), ("launch.substitutions", "FileContent"),
    ("launch.substitutions", "IfElseSubstitution"), ("launch.substitutions", "AllSubstitution"),
    ("launch.utilities", "perform_substitutions"),
    ("launch.utilities", "normalize_to_list_of_substitutions"),
    ("launch.utilities.type_utils", "perform_typed_substitution"),
    ("launch.events", "Shutdown"), ("launch.events", "matches_action"),
    ("launch.events.process", "ProcessExited"), ("launch.events.process", "ShutdownProcess"),
    ("launch.actions", "AppendEnvironmentVariable"), ("launch.actions", "ExecuteLocal"),
    ("launch.actions", "PushEnvironment"), ("launch.actions", "ResetLaunchConfigurations"),
    ("launch.descriptions", "Executable"),
    ("launch.launch_description_sources", "PythonLaunchDescriptionSource"),
    ("launch.conditions", "evaluate_condition_expression"),
    ("launch_ros.actions", "SetParametersFromFile"), ("launch_ros.actions", "SetUseSimTime"),
    ("launch_ros.actions.node", "Node"),
    ("launch_ros.descriptions", "ParameterFile"), ("launch_ros.descriptions", "ComposableNode"),
    ("launch_ros.descriptions", "ParameterValue"),
    ("launch_ros.parameter_descriptions", "ParameterValue"),
    ("launch_ros.substitutions", "FindPackageShare"),
    ("launch_ros.substitutions", "FindPackagePrefix"),
    ("launch_ros.substitutions", "ExecutableInPackage"),
    ("launch_ros.utilities", "make_namespace_absolute"),
]


@pytest.mark.parametrize(("module", "name"), REAL_IMPORTS)
def test_names_import_from_where_launch_defines_them(module, name):
    with compat_modules():
        mod = importlib.import_module(module)
        assert getattr(mod, name) is not None
        # `import launch` then `launch.utilities.x`: parents carry their submodules
        root = importlib.import_module(module.split(".")[0])
        for part in module.split(".")[1:]:
            root = getattr(root, part)
        assert getattr(root, name) is getattr(mod, name)


def test_every_table_row_is_importable_or_says_it_is_unsupported():
    with compat_modules():
        for module, name, obj in NAMES:
            mod = importlib.import_module(module)
            package = importlib.import_module(module.rsplit(".", 1)[0]) if "." in module \
                else mod
            if obj is UNSUPPORTED:
                with pytest.raises(AttributeError, match=f"does not support {module}.{name}"):
                    getattr(mod, name)
            else:
                assert getattr(mod, name) is obj and getattr(package, name) is obj


@pytest.mark.parametrize(("statement", "missing"), [
    ("from launch.actions import UnregisterEventHandler",
     "launch.actions.UnregisterEventHandler"),
    ("from launch_ros.actions import NoSuchThing", "launch_ros.actions.NoSuchThing"),
    ("import launch_ros.no_such_module", "launch_ros.no_such_module"),
    ("import launch.actions\nlaunch.actions.Nope", "launch.actions.Nope"),
])
def test_a_missing_name_says_tuilaunch_lacks_it(write, statement, missing):
    path = write(f"""
from launch import LaunchDescription
{statement}

def generate_launch_description():
    return LaunchDescription([])
""")
    with pytest.raises(LaunchError) as info:
        load_file(str(path))
    text = str(info.value)
    assert f"tuilaunch does not support {missing} yet" in text
    assert f"{path.name}:" in text and "install" not in text


@pytest.fixture
def extension(tmp_path, monkeypatch):
    root = install_extension(tmp_path / "ext")
    monkeypatch.syspath_prepend(str(root))
    yield root
    for name in [n for n in sys.modules if n.startswith("fake_nav_common")]:
        del sys.modules[name]


def test_third_party_substitution_rewrites_a_params_file_for_a_parameter_file(
        write, tmp_path, extension):
    params = tmp_path / "params.yaml"
    params.write_text(yaml.safe_dump({"amcl": {"ros__parameters": {
        "use_sim_time": False, "base_frame_id": "base", "max_particles": 2000,
        "map_topic": "$(var map_topic)"}}}))
    path = write(f"""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from launch_ros.descriptions import ParameterFile
from fake_nav_common.launch import RewrittenParams

def generate_launch_description():
    configured = ParameterFile(RewrittenParams(
        source_file=LaunchConfiguration('params_file'), root_key=LaunchConfiguration('namespace'),
        param_rewrites={{'use_sim_time': LaunchConfiguration('use_sim_time'),
                         'max_particles': '500'}}, convert_types=True), allow_substs=True)
    return LaunchDescription([
        DeclareLaunchArgument('namespace', default_value=''),
        DeclareLaunchArgument('use_sim_time', default_value='false'),
        DeclareLaunchArgument('map_topic', default_value='map'),
        DeclareLaunchArgument('params_file', default_value='{params}'),
        Node(package='tuilaunch_demos', executable='talker', name='amcl',
             namespace=LaunchConfiguration('namespace'), parameters=[configured]),
    ])
""")
    plan = plan_of(path, namespace="r1", use_sim_time="true", map_topic="/r1/map")
    (node,) = plan.processes
    assert node.full_name == "/r1/amcl"
    (file,) = node.parameter_files
    assert node.cmd[node.cmd.index("--params-file") + 1] == file
    data = yaml.safe_load(Path(file).read_text())
    assert data == {"r1": {"amcl": {"ros__parameters": {
        "use_sim_time": True, "base_frame_id": "base", "max_particles": 500,
        "map_topic": "/r1/map"}}}}


def test_condition_evaluate_is_a_bool_for_extensions(write, tmp_path, extension):
    source = tmp_path / "robot.txt"
    source.write_text("name: ROBOT\n")
    path = write(f"""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, LogInfo
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration, FileContent
from fake_nav_common.launch import ReplaceText

def generate_launch_description():
    text = ReplaceText('{source}', {{'ROBOT': LaunchConfiguration('robot')}},
                       condition=IfCondition(LaunchConfiguration('rename')))
    return LaunchDescription([
        DeclareLaunchArgument('robot', default_value='tb3'),
        DeclareLaunchArgument('rename', default_value='false'),
        LogInfo(msg=FileContent(text)),
    ])
""")
    assert plan_of(path).actions[0].data == "name: ROBOT\n"
    assert plan_of(path, rename="true").actions[0].data == "name: tb3\n"


def test_third_party_action_execute_runs_with_the_context(write, extension):
    path = write("""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import UnlessCondition
from launch.substitutions import LaunchConfiguration
from fake_nav_common.launch import EchoAction

def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('word', default_value='hello'),
        EchoAction(LaunchConfiguration('word')),
        EchoAction('never', condition=UnlessCondition('true')),
    ])
""")
    plan = plan_of(path, word="bonjour")
    assert [a.data for a in plan.actions] == ["echo bonjour"]


def test_an_error_inside_an_extension_names_its_file_and_line(write, extension):
    path = write("""
from launch import LaunchDescription
from launch.actions import LogInfo
from fake_nav_common.launch import Broken

def generate_launch_description():
    return LaunchDescription([LogInfo(msg=Broken())])
""")
    with pytest.raises(LaunchError) as info:
        plan_of(path)
    text = str(info.value)
    assert "KeyError" in text and "extension.py:" in text


def test_custom_substitution_receives_launch_context_api(write):
    path = write("""
import os
from launch import LaunchDescription, Substitution
from launch.actions import DeclareLaunchArgument, LogInfo
from launch.utilities import perform_substitutions
from launch.substitutions import LaunchConfiguration

class Describe(Substitution):
    def perform(self, context):
        local = context.get_locals_as_dict()
        return ' '.join([context.launch_configurations['who'],
                         context.perform_substitution(LaunchConfiguration('who')),
                         perform_substitutions(context, [LaunchConfiguration('who'), '!']),
                         os.path.basename(local['current_launch_file_path']),
                         context.environment.get('TUILAUNCH_TEST_VAR', 'unset')])

def generate_launch_description():
    return LaunchDescription([DeclareLaunchArgument('who', default_value='me'),
                              LogInfo(msg=Describe())])
""")
    plan = plan_of(path, who="you")
    assert plan.actions[0].data == f"you you you! {path.name} unset"


def test_launch_configurations_set_by_an_opaque_function_reach_what_follows(write):
    path = write("""
from launch import LaunchDescription
from launch.actions import OpaqueFunction, LogInfo
from launch.substitutions import LaunchConfiguration

def setup(context):
    context.launch_configurations['robot_name'] = 'tb3_' + context.launch_configurations['n']
    return []

def generate_launch_description():
    return LaunchDescription([OpaqueFunction(function=setup),
                              LogInfo(msg=LaunchConfiguration('robot_name'))])
""")
    assert plan_of(path, n="7").actions[0].data == "tb3_7"


def test_user_files_do_not_inherit_tuilaunchs_future_flags(write):
    path = write("""
from launch import LaunchDescription
from launch.actions import LogInfo

def f() -> int:
    return 1

def generate_launch_description():
    return LaunchDescription([LogInfo(msg=type(f.__annotations__['return']).__name__)])
""")
    assert plan_of(path).actions[0].data == "type"  # not postponed into the string 'int'


def test_sys_argv_looks_like_ros2_launch(tmp_path):
    prefix = tmp_path / "prefix"
    share = make_package(prefix, "fake_multi", files={"launch/multi_launch.py": """
        import sys
        from launch import LaunchDescription
        from launch.actions import DeclareLaunchArgument, LogInfo
        from fake_nav_common.launch import RobotPoses

        def generate_launch_description():
            robots = RobotPoses('robots').value()
            return LaunchDescription(
                [DeclareLaunchArgument('robots', default_value='')]
                + [LogInfo(msg=f"{name} at {pose['x']}") for name, pose in robots.items()]
                + [LogInfo(msg=' '.join(sys.argv[:4]))])
        """})
    ext = install_extension(tmp_path / "ext")
    env = world_env(prefix, ext, tmp_path)
    done = run_cli("fake_multi", "multi_launch.py", "robots:=a={x: 1.0};b={x: 2.5}",
                   "--print", "--json", env=env)
    assert done.returncode == 0, done.stderr
    logs = [a["data"] for a in json.loads(done.stdout)["actions"]]
    assert logs == ["a at 1.0", "b at 2.5", "ros2 launch fake_multi multi_launch.py"]
    assert share.is_dir()


def test_environment_and_configuration_stacks_and_predicate_conditions(write, monkeypatch):
    monkeypatch.setenv("PROBE_PATHS", "/base")
    path = write("""
from launch import Condition, LaunchDescription
from launch.actions import (AppendEnvironmentVariable, DeclareLaunchArgument, ExecuteProcess,
                            PopEnvironment, PopLaunchConfigurations, PushEnvironment,
                            PushLaunchConfigurations, LogInfo, SetEnvironmentVariable,
                            SetLaunchConfiguration, UnsetLaunchConfiguration)
from launch.substitutions import LaunchConfiguration

def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('mode', default_value='fast'),
        AppendEnvironmentVariable('PROBE_PATHS', '/after'),
        AppendEnvironmentVariable('PROBE_PATHS', '/before', prepend=True, separator=';'),
        PushEnvironment(),
        SetEnvironmentVariable('PROBE_INNER', '1'),
        ExecuteProcess(cmd=['true'], name='inner'),
        PopEnvironment(),
        ExecuteProcess(cmd=['true'], name='outer'),
        PushLaunchConfigurations(),
        SetLaunchConfiguration('mode', 'slow'),
        UnsetLaunchConfiguration('other'),
        LogInfo(msg=LaunchConfiguration('mode')),
        PopLaunchConfigurations(),
        LogInfo(msg=LaunchConfiguration('mode')),
        LogInfo(msg='only when fast', condition=Condition(
            predicate=lambda context: context.launch_configurations['mode'] == 'fast')),
        LogInfo(msg='never', condition=Condition(predicate=lambda context: False)),
    ])
""")
    plan = plan_of(path)
    inner, outer = plan.processes
    assert inner.env == {"PROBE_PATHS": "/before;/base:/after", "PROBE_INNER": "1"}
    assert outer.env == {"PROBE_PATHS": "/before;/base:/after"}
    assert [a.data for a in plan.actions if a.enabled] == ["slow", "fast", "only when fast"]


def test_parameter_substitution_reads_set_parameter(write):
    path = write("""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, LogInfo
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import SetParameter, SetUseSimTime
from launch_ros.substitutions import Parameter

def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument('rate', default_value='10'),
        SetParameter('rate', LaunchConfiguration('rate')),
        SetUseSimTime(True),
        LogInfo(msg=[Parameter('rate'), ' ', Parameter('use_sim_time'), ' ',
                     Parameter('missing', default='none')]),
    ])
""")
    assert plan_of(path, rate="30").actions[0].data == "30 true none"


def test_an_extension_failing_while_the_file_loads_names_both_places(write, tmp_path, extension):
    path = write("""
from launch import LaunchDescription
from fake_nav_common.launch import Broken

def generate_launch_description():
    Broken().perform(None)
    return LaunchDescription([])
""")
    with pytest.raises(LaunchError) as info:
        load_file(str(path))
    text = str(info.value)
    assert f"{path.name}:6" in text and "extension.py:" in text and "KeyError" in text
