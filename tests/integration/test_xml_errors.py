"""Mistakes in XML and YAML launch files: one line naming file, line, column, tag, attribute."""

from __future__ import annotations

import pytest

from tuilaunch.engine import LaunchError, load_file

from ..conftest import EXAMPLES, plan_of, run_cli


def error_of(write, text: str, name: str = "bad.launch.xml") -> LaunchError:
    path = write(text, name)
    with pytest.raises(LaunchError) as exc:
        plan_of(path)
    return exc.value


@pytest.mark.parametrize("text, where, message", [
    ('<launch>\n  <foo bar="1"/>\n</launch>', (2, 3),
     "<foo>: unknown tag: not a launch or launch_ros action (a third-party launch extension?)"),
    ('<launch>\n  <node pkg="tuilaunch_demos"/>\n</launch>', (2, 3),
     "<node>: attribute 'exec' is required"),
    ('<launch>\n <node pakg="tuilaunch_demos" exec="talker"/>\n</launch>', (2, 8),
     "<node>: unexpected attribute(s): pakg"),
    ('<launch>\n  <node exec="talker">\n    <parm name="a" value="1"/>\n  </node>\n</launch>',
     (3, 5), "<node>: unexpected nested tag(s): <parm> (did you mean <param>?)"),
    ('<launch>\n  <log message="$(var robot"/>\n</launch>', (2, 8),
     "<log>: attribute 'message': $(var ... is not closed with ')' (at character 1 of "
     "'$(var robot')"),
    ('<launch>\n  <log message="x $(vra robot)"/>\n</launch>', (2, 8),
     "<log>: attribute 'message': unknown substitution $(vra); known: all, and, anon"),
    ('<launch>\n  <log message="$(var)"/>\n</launch>', (2, 8),
     "$(var) takes 1 to 2 argument(s), got 0"),
    ('<launch>\n  <log message="$(eval \'1 + 1)"/>\n</launch>', (2, 8), "quote ' is not closed"),
    ('<launch>\n  <node exec="a" if="true" unless="false"/>\n</launch>', (2, 28),
     "'if' and 'unless' cannot be used together"),
    ('<launch>\n  <node exec="a"><param name="p" value="1" type="integer"/></node>\n</launch>',
     (2, 44), "type 'integer' is not one of str, int, float, bool"),
    ('<launch>\n  <node exec="a"><param name="n" value="many" type="int"/></node>\n'
     '</launch>', (2, 34), "<param>: value 'many' is not an integer"),
    ('<launch>\n  <node exec="a"><param value="1"/></node>\n</launch>', (2, 18),
     "<param>: needs a 'name'"),
    ('<launch>\n  <timer period="soon"><log message="x"/></timer>\n</launch>', (2, 3),
     "TimerAction period 'soon' is not a number"),
    ('<launch>\n  <executable cmd="true" respawn_delay="-1"/>\n</launch>', (2, 26),
     "attribute 'respawn_delay' must not be negative"),
    ('<launch>\n  <node exec="a"\n</launch>', (3, 1), "not well-formed XML"),
    ('<launch>\n  <log message="a & b"/>\n</launch>', (2, 20), "not well-formed XML"),
    ('<robot name="r"/>', (1, 1), "the root tag is <robot>, expected <launch>"),
    ('<launch>\n  <arg name="m" default="x"><choice value="a"/></arg>\n</launch>', (2, 17),
     "default 'x' is not one of the choices: a"),
])
def test_xml_mistakes_name_the_place_and_what_is_wrong(write, text, where, message):
    error = error_of(write, text)
    assert message in error.message
    assert error.origin is not None
    # TimerAction's period is read when the plan resolves: that error has the line only
    assert (error.origin.line, error.origin.column or where[1]) == where


@pytest.mark.parametrize("text, where, message", [
    ("launch:\n- node:\n    pkg: tuilaunch_demos\n   exec: talker\n", (4, 4), "not valid YAML"),
    ("launch:\n- nod:\n    exec: talker\n", (2, 3), "<nod>: unknown tag (did you mean <node>?)"),
    ("launch:\n- node:\n    exec: talker\n    pkgg: x\n", (4, 5),
     "<node>: unexpected attribute(s): pkgg (did you mean pkg?)"),
    ("launch:\n- node:\n    pkg: tuilaunch_demos\n", (2, 3), "attribute 'exec' is required"),
    ("launch:\n- node:\n    exec: talker\n    param:\n    - name: a\n      value: $(bad)\n",
     (6, 7), "unknown substitution $(bad)"),
    ("nodes:\n- node: {exec: talker}\n", (1, 1), "the root key is 'nodes', expected 'launch'"),
    ("launch:\n- node: {exec: talker}\n  pkg: x\n", (2, 3),
     "each action is a mapping with one key, its tag"),
    ("launch:\n- node: {exec: talker\n", (3, 1), "not valid YAML"),
    ("launch:\n- node: {exec: talker}\n  log: {message: x}\n", (2, 3),
     "each action is a mapping with one key"),
])
def test_yaml_mistakes_name_the_place_and_what_is_wrong(write, text, where, message):
    error = error_of(write, text, "bad.launch.yaml")
    assert message in error.message
    assert error.origin is not None and (error.origin.line, error.origin.column) == where


def test_errors_in_an_included_file_name_that_file(write):
    write('<launch>\n\n  <node pkg="tuilaunch_demos" exec="talker" colour="red"/>\n</launch>',
          "child.launch.xml")
    error = error_of(write, '<launch>\n  <include file="$(dirname)/child.launch.xml"/>\n'
                     '</launch>')
    assert error.origin is not None and error.origin.file.endswith("child.launch.xml")
    assert (error.origin.line, error.origin.column) == (3, 45)  # the attribute itself
    assert "unexpected attribute(s): colour" in error.message


def test_non_boolean_condition_names_the_argument_and_line(write):
    path = write('<launch>\n  <arg name="gui" default="true"/>\n'
                 '  <node exec="rviz2" if="$(var gui)"/>\n</launch>', "c.launch.xml")
    with pytest.raises(LaunchError, match="argument 'gui' = 'maybe' is used as a condition")\
            as exc:
        plan_of(path, gui="maybe")
    assert exc.value.origin is not None and exc.value.origin.line == 3


def test_the_command_line_reports_one_line_without_traceback(write):
    path = write('<launch>\n  <node pkg="tuilaunch_demos" exec="talker">\n'
                 '    <param name="rate" valeu="2"/>\n  </node>\n</launch>', "cli.launch.xml")
    done = run_cli(str(path), "--print")
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    first = done.stderr.splitlines()[0]
    assert first.startswith("tuilaunch: error: ") and "cli.launch.xml:3:24: <param>:" in first
    assert "unexpected attribute(s): valeu" in first


def test_a_missing_package_is_a_plan_problem_not_a_load_error(write):
    path = write('<launch>\n  <node pkg="no_such_pkg" exec="driver"/>\n'
                 '  <node pkg="tuilaunch_demos" exec="talker"/>\n</launch>', "p.launch.xml")
    loaded = load_file(str(path))
    assert len(loaded.entities) == 2
    done = run_cli(str(path), "--print")
    assert done.returncode == 3 and "Traceback" not in done.stderr
    assert "p.launch.xml:2: driver-1" in done.stderr and "no_such_pkg" in done.stderr


def test_an_undeclared_variable_names_itself_and_how_to_declare_it(write):
    path = write('<launch>\n  <node pkg="tuilaunch_demos" exec="talker" name="$(var who)"/>\n'
                 '</launch>', "v.launch.xml")
    done = run_cli(str(path), "--print")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "v.launch.xml:2:45: launch argument 'who' is used but has no value" in done.stderr
    assert 'hint: declare it with <arg name="who" default="..."/> or pass who:=value' in \
        done.stderr
    assert run_cli(str(path), "--print", "who:=me").returncode == 0


def test_an_attribute_on_a_later_line_of_its_tag_is_placed_exactly(write):
    error = error_of(write, '<launch>\n  <node pkg="tuilaunch_demos"\n        exec="talker"\n'
                     '        args="--a $(var x"/>\n</launch>')
    assert error.origin is not None and (error.origin.line, error.origin.column) == (4, 9)
    assert "<node>: attribute 'args'" in error.message


# --- attributes ros2 launch refuses (launch's assert_entity_completely_parsed) -----------

@pytest.mark.parametrize("text, where, message", [
    ('<launch>\n  <group ns="robot">\n    <log message="x"/>\n  </group>\n</launch>', (2, 10),
     "<group>: unexpected attribute(s): ns (a group takes no namespace in ros2 launch: put "
     '<push_ros_namespace namespace="..."/> first inside the group)'),
    ('<launch>\n  <group namespace="robot"/>\n</launch>', (2, 10),
     "<group>: unexpected attribute(s): namespace (a group takes no namespace"),
    ('<launch>\n  <node pkg="tuilaunch_demos" exec="talker" ns="r1"/>\n</launch>', (2, 45),
     "<node>: unexpected attribute(s): ns (did you mean namespace? ns is ROS 1's spelling)"),
    ('<launch>\n  <node pkg="tuilaunch_demos" exec="talker" nmae="t"/>\n</launch>', (2, 45),
     "<node>: unexpected attribute(s): nmae (did you mean name?)"),
    ('<launch>\n  <node exec="a"><param name="p" value="1" tpye="int"/></node>\n</launch>',
     (2, 44), "<param>: unexpected attribute(s): tpye (did you mean type?)"),
    ('<launch>\n  <arg name="a" defualt="1"/>\n</launch>', (2, 17),
     "<arg>: unexpected attribute(s): defualt (did you mean default?)"),
    ('<launch>\n  <include file="x.launch.xml" flie="y"/>\n</launch>', (2, 32),
     "<include>: unexpected attribute(s): flie (did you mean file?)"),
    ('<launch>\n  <let name="a" value="1" vlaue="2"/>\n</launch>', (2, 27),
     "<let>: unexpected attribute(s): vlaue (did you mean value?)"),
    ('<launch>\n  <executable cmd="true" respwan="true"/>\n</launch>', (2, 26),
     "<executable>: unexpected attribute(s): respwan (did you mean respawn?)"),
    ('<launch>\n  <log message="x" level="warn"/>\n</launch>', (2, 20),
     "<log>: unexpected attribute(s): level"),
])
def test_attributes_ros2_launch_refuses_are_refused(write, text, where, message):
    error = error_of(write, text)
    assert message in error.message
    assert error.origin is not None
    assert (error.origin.line, error.origin.column) == where


def test_yaml_group_namespace_is_refused_with_what_to_write(write):
    error = error_of(write, "launch:\n- group:\n    ns: robot\n    children:\n"
                     "    - log: {message: x}\n", "bad.launch.yaml")
    assert "<group>: unexpected attribute(s): ns (a group takes no namespace" \
        in error.message
    assert error.origin is not None and (error.origin.line, error.origin.column) == (3, 5)
    error = error_of(write, "launch:\n- node: {exec: talker, ns: r1}\n", "bad2.launch.yaml")
    assert "<node>: unexpected attribute(s): ns (did you mean namespace?" in error.message


def test_the_group_namespace_error_reaches_the_command_line_as_one_line(write):
    path = write('<launch>\n  <group ns="robot">\n    <node pkg="tuilaunch_demos" '
                 'exec="talker"/>\n  </group>\n</launch>', "ns.launch.xml")
    done = run_cli(str(path), "--print")
    assert done.returncode == 2 and "Traceback" not in done.stderr
    first = done.stderr.splitlines()[0]
    assert "ns.launch.xml:2:10: <group>: unexpected attribute(s): ns" in first


def test_every_attribute_ros2_launch_reads_is_still_accepted(write):
    """The attributes launch's and launch_ros's parse() read, tag by tag."""
    path = write('''<launch>
  <arg name="a" default="x" description="d"><choice value="x"/></arg>
  <let name="b" value="1"/>
  <set_env name="E" value="1"/>
  <append_env name="E" value="2" prepend="true" separator=":"/>
  <unset_env name="F"/>
  <group scoped="true" forwarding="false" if="true">
    <keep name="a" value="y"/>
    <push_ros_namespace namespace="fleet"/>
    <node pkg="tuilaunch_demos" exec="talker" name="t" namespace="ns" exec_name="tk"
          args="--x" ros_args="--log-level info" output="screen" respawn="false"
          respawn_delay="1.0" respawn_max_retries="2" launch-prefix="" cwd="/tmp"
          sigterm_timeout="5" sigkill_timeout="5" emulate_tty="true" on_exit="shutdown"
          unless="false">
      <param name="p" value="1" type="int"/>
      <param name="q" value="a,b" value-sep=","/>
      <remap from="a" to="b"/>
      <env name="X" value="1"/>
    </node>
  </group>
  <executable cmd="true" name="e" cwd="/tmp" shell="false" output="log" emulate_tty="false"
              launch-prefix="" respawn="false" sigterm_timeout="1" sigkill_timeout="1"/>
  <timer period="1.0" cancel_on_shutdown="true"><log message="m"/></timer>
  <set_parameter name="x" value="1"/>
  <set_remap from="c" to="d"/>
  <shutdown reason="r" if="false"/>
</launch>''', "all.launch.xml")
    plan = plan_of(path)
    assert any(p.name == "t" for p in plan.processes)


def test_the_example_launch_files_still_load():
    for path in sorted((EXAMPLES / "launch").glob("*.launch.*")):
        if path.suffix in (".xml", ".yaml"):
            assert load_file(str(path)).entities, path
