"""`$(...)` substitutions in XML and YAML launch files, performed as launch performs them."""

from __future__ import annotations

import os
import shutil

import pytest

from tuilaunch.engine import LaunchError
from tuilaunch.engine.packages import package_prefix, package_share

from ..conftest import plan_of


def logged(write, body: str, name: str = "subs.launch.xml", **arguments: str) -> list[str]:
    """The messages of `<log>` actions: each a performed substitution."""
    path = write(f"<launch>\n{body}\n</launch>\n", name)
    plan = plan_of(path, **arguments)
    return [a.data for a in plan.actions if a.kind == "log"]


def test_var_with_and_without_default_and_nested_names(write):
    assert logged(write, """
  <arg name="robot" default="r2"/>
  <arg name="key" default="robot"/>
  <log message="$(var robot)"/>
  <log message="$(var missing fallback)"/>
  <log message="$(var $(var key))"/>
  <log message="pre-$(var robot)-post"/>
""", robot="r9") == ["r9", "fallback", "r9", "pre-r9-post"]


def test_env_and_optenv(write, monkeypatch):
    monkeypatch.setenv("TUILAUNCH_SET", "here")
    monkeypatch.delenv("TUILAUNCH_UNSET", raising=False)
    assert logged(write, """
  <log message="$(env TUILAUNCH_SET)"/>
  <log message="$(env TUILAUNCH_UNSET default_value)"/>
  <log message="[$(optenv TUILAUNCH_UNSET)]"/>
  <log message="$(optenv TUILAUNCH_SET other)"/>
  <log message="$(optenv TUILAUNCH_UNSET 'two words')"/>
""") == ["here", "default_value", "[]", "here", "two words"]
    with pytest.raises(LaunchError, match="environment variable 'TUILAUNCH_UNSET' is not set")\
            as exc:
        logged(write, '\n<log message="$(env TUILAUNCH_UNSET)"/>', "bad.launch.xml")
    assert exc.value.origin is not None and exc.value.origin.line == 3


def test_find_pkg_share_prefix_exec_and_exec_in_pkg(write):
    share, prefix = package_share("tuilaunch_demos"), package_prefix("tuilaunch_demos")
    assert logged(write, """
  <log message="$(find-pkg-share tuilaunch_demos)"/>
  <log message="$(find-pkg-prefix tuilaunch_demos)"/>
  <log message="$(find-exec sh)"/>
  <log message="$(exec-in-pkg talker tuilaunch_demos)"/>
  <log message="$(find-pkg-share tuilaunch_demos)/config/talker.yaml"/>
""") == [str(share), str(prefix), shutil.which("sh"), str(prefix / "lib/tuilaunch_demos/talker"),
         str(share / "config/talker.yaml")]
    with pytest.raises(LaunchError, match="no_such_package"):
        logged(write, '<log message="$(find-pkg-share no_such_package)"/>', "bad.launch.xml")


def test_file_content(write, tmp_path):
    (tmp_path / "robot.urdf").write_text("<robot name='r'/>\n")
    assert logged(write, """
  <log message="$(file-content $(dirname)/robot.urdf)"/>
""") == ["<robot name='r'/>\n"]


def test_eval_with_quotes_nesting_and_modules(write):
    assert logged(write, """
  <arg name="n" default="3"/>
  <log message="$(eval '$(var n) * 2')"/>
  <log message="$(eval &quot;'a b' + 'c'&quot;)"/>
  <log message="$(eval 'math.floor(2.7)' math)"/>
  <log message="$(eval '$(var n) > 2 and true')"/>
""") == ["6", "a bc", "2", "True"]


def test_command_runs_at_resolve_time_and_xacro_gives_the_robot_description(write):
    messages = logged(write, """
  <log message="$(command 'echo one  two')"/>
  <let name="xacro" value="$(find-pkg-share tuilaunch_demos)/urdf/turret.xacro"/>
  <log message="$(command '$(find-exec xacro) $(var xacro) prefix:=r2/')"/>
""")
    assert messages[0] == "one two\n"
    assert '<link name="r2/base_link"/>' in messages[1]
    with pytest.raises(LaunchError, match="command 'false' failed"):
        logged(write, '<log message="$(command false)"/>', "bad.launch.xml")


def test_anon_dirname_filename(write, tmp_path):
    a, b, c, here, name = logged(write, """
  <log message="$(anon node)"/>
  <log message="$(anon node)"/>
  <log message="$(anon other)"/>
  <log message="$(dirname)"/>
  <log message="$(filename)"/>
""")
    assert a.startswith("node_") and a == b and c.startswith("other_") and a != c
    assert here == str(tmp_path) and name == str(tmp_path / "subs.launch.xml")


def test_boolean_substitutions_nest(write):
    assert logged(write, """
  <arg name="a" default="true"/>
  <arg name="b" default="false"/>
  <log message="$(not $(var a))"/>
  <log message="$(and $(var a) $(var b))"/>
  <log message="$(or $(var a) $(var b))"/>
  <log message="$(equals $(var a) true)"/>
  <log message="$(not $(equals $(var b) true))"/>
  <log message="$(not-equals $(var a) $(var b))"/>
  <log message="$(if $(var a) yes no)"/>
  <log message="$(any $(var b) $(var b) $(var a))"/>
  <log message="$(all $(var a) $(var a) $(var b))"/>
  <log message="$(equals $(var a) True) $(equals 1.0 1) $(not-equals 1 true) $(equals a A)"/>
""") == ["false", "false", "true", "true", "true", "true", "yes", "true", "false",
         "true true false false"]  # launch compares booleans and numbers by value


def test_conditions_take_substitutions(write):
    path = write("""<launch>
  <arg name="mode" default="fast"/>
  <node pkg="tuilaunch_demos" exec="talker" name="fast" if="$(equals $(var mode) fast)"/>
  <node pkg="tuilaunch_demos" exec="talker" name="slow" unless="$(equals $(var mode) fast)"/>
</launch>""", "cond.launch.xml")
    assert [p.enabled for p in plan_of(path).processes] == [True, False]
    assert [p.enabled for p in plan_of(path, mode="slow").processes] == [False, True]


def test_escapes_and_literal_dollars(write):
    assert logged(write, r"""
  <log message="\$(var x) is literal"/>
  <log message="cost: $5 (approx)"/>
  <log message="$(eval '\'q\' + \'r\'')"/>
""") == ["$(var x) is literal", "cost: $5 (approx)", "qr"]


def test_substitutions_in_yaml_files(write, monkeypatch):
    monkeypatch.setenv("TUILAUNCH_SET", "here")
    path = write("""
launch:
- arg: {name: n, default: "3"}
- log: {message: "$(eval '$(var n) + 1') $(env TUILAUNCH_SET) $(optenv NOT_SET_AT_ALL x)"}
""", "subs.launch.yaml")
    plan = plan_of(path)
    assert [a.data for a in plan.actions] == ["4 here x"]
    assert os.path.basename(plan.file) == "subs.launch.yaml"


def test_param_reads_a_set_parameter_in_scope(write):
    path = write("""<launch>
  <set_parameter name="vehicle_height" value="2.5"/>
  <arg name="margin" default="0.5"/>
  <node pkg="tuilaunch_demos" exec="talker">
    <param name="max_z" value="$(eval '$(param vehicle_height) + $(var margin)')"/>
    <param name="other" value="$(param missing 7)"/>
  </node>
  <log message="$(param nowhere)"/>
</launch>""", "param.launch.xml")
    with pytest.raises(LaunchError, match=r"\$\(param nowhere\): no SetParameter") as exc:
        plan_of(path)
    assert exc.value.origin is not None and exc.value.origin.line == 8
    path.write_text(path.read_text().replace('  <log message="$(param nowhere)"/>\n', ""))
    talker = plan_of(path).processes[0]
    assert talker.parameters == {"vehicle_height": 2.5, "max_z": 3.0, "other": 7}
