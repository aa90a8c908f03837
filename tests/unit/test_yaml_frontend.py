"""YAML launch files: the same tags as XML, with YAML's own types."""

from __future__ import annotations

from ..conftest import EXAMPLES, plan_of

LAUNCH = EXAMPLES / "launch"


def test_ros2_demos_talker_listener_yaml_resolves_like_the_xml_one():
    from_yaml = plan_of(LAUNCH / "talker_listener.launch.yaml")
    from_xml = plan_of(LAUNCH / "talker_listener.launch.xml")
    assert [(p.package, p.executable, p.name, p.namespace, p.cmd) for p in from_yaml.processes] \
        == [(p.package, p.executable, p.name, p.namespace, p.cmd) for p in from_xml.processes]
    assert [p.origin.line for p in from_yaml.processes if p.origin] == [3, 7]


def test_every_tag_in_yaml(write, tmp_path):
    write('<launch><arg name="who"/><node pkg="tuilaunch_demos" exec="talker" '
          'name="$(var who)"/></launch>', "child.launch.xml")
    params = tmp_path / "p.yaml"
    params.write_text("/**:\n  ros__parameters:\n    from_file: true\n")
    path = write(f"""
launch:
- arg:
    name: robot
    default: r2
    description: the robot
- arg:
    name: mode
    default: a
    choice: [{{value: a}}, {{value: b}}]
- arg: {{name: gui, default: "false"}}
- let: {{name: topic, value: "/$(var robot)/chatter"}}
- include:
    file: "$(dirname)/child.launch.xml"
    arg:
    - {{name: who, value: included}}
- group:
    scoped: true
    children:
    - push-ros-namespace: {{namespace: "$(var robot)"}}
    - set_env: {{name: MODE, value: "$(var mode)"}}
    - node:
        pkg: tuilaunch_demos
        exec: talker
        name: talker
        args: --verbose $(var mode)
        respawn: "true"
        respawn_delay: 1
        param:
        - {{name: an_int, value: 1}}
        - {{name: a_str, value: "1"}}
        - {{name: a_list, value: [1.5, 2.5]}}
        - {{name: a_bool, value: true}}
        - {{name: from_arg, value: "$(var robot)"}}
        - name: outer
          param:
          - {{name: inner, value: 2}}
        - from: {params}
        remap:
        - {{from: chatter, to: "$(var topic)"}}
        env:
        - {{name: COLOR, value: blue}}
    - node: {{pkg: tuilaunch_demos, exec: listener, if: "$(var gui)"}}
- group:
  - push_ros_namespace: {{namespace: second}}
  - executable: {{cmd: "echo $(var robot)", name: echo, shell: false}}
- timer:
    period: 2
    children:
    - log: {{message: "two seconds after start"}}
""", "all.launch.yaml")
    plan = plan_of(path)
    assert [a.name for a in plan.arguments][:3] == ["robot", "mode", "gui"]
    assert next(a for a in plan.arguments if a.name == "mode").choices == ["a", "b"]
    included, talker, listener, echo = plan.processes
    assert included.full_name == "/included"
    assert talker.full_name == "/r2/talker"
    assert talker.parameters == {"an_int": 1, "a_str": "1", "a_list": [1.5, 2.5],
                                 "a_bool": True, "from_arg": "r2", "outer.inner": 2}
    assert talker.parameter_files == [str(params)]
    assert talker.remappings == [["chatter", "/r2/chatter"]]
    assert talker.env == {"MODE": "a", "COLOR": "blue"}
    assert talker.cmd[1:3] == ["--verbose", "a"]
    assert (talker.respawn, talker.respawn_delay) == (True, 1.0)
    assert not listener.enabled and plan_of(path, gui="true").processes[2].enabled
    assert (echo.cmd, echo.namespace) == (["echo", "r2"], "/second")
    log = plan.actions[0]
    assert log.data == "two seconds after start"
    assert log.trigger is not None and log.trigger.delay == 2.0
    assert talker.origin is not None and talker.origin.line == 22


def test_xml_includes_yaml_and_yaml_includes_xml(write):
    write("launch:\n- arg: {name: n, default: y}\n"
          "- node: {pkg: tuilaunch_demos, exec: talker, name: 'y_$(var n)'}\n", "c.launch.yaml")
    write('<launch><arg name="n" default="x"/>'
          '<node pkg="tuilaunch_demos" exec="listener" name="x_$(var n)"/></launch>',
          "c.launch.xml")
    from_xml = write('<launch><include file="$(dirname)/c.launch.yaml">'
                     '<arg name="n" value="1"/></include></launch>', "p.launch.xml")
    from_yaml = write("launch:\n- include:\n    file: $(dirname)/c.launch.xml\n"
                      "    arg: [{name: n, value: '2'}]\n", "p.launch.yaml")
    assert [p.full_name for p in plan_of(from_xml).processes] == ["/y_1"]
    assert [p.full_name for p in plan_of(from_yaml).processes] == ["/x_2"]


def test_ros_docs_style_yaml_with_version_header_eval_condition_and_timer(write):
    path = write("""%YAML 1.2
---
launch:
- arg:
    name: "sim_ns"
    default: "sim1"
- arg:
    name: "use_red"
    default: "False"
- arg:
    name: "red"
    default: "200"
- node:
    pkg: "tuilaunch_demos"
    namespace: "$(var sim_ns)"
    exec: "talker"
    name: "sim"
- executable:
    cmd: "echo call $(var sim_ns)/spawn \\"{x: 2, y: 2}\\""
- timer:
    period: 2.0
    children:
    - executable:
        cmd: "echo set $(var sim_ns)/sim red $(var red)"
        if: "$(eval '$(var red) == 200 and $(var use_red)')"
""", "docs.launch.yaml")
    plan = plan_of(path)
    sim, call, later = plan.processes
    assert sim.full_name == "/sim1/sim"
    assert call.cmd == ["echo", "call", "sim1/spawn", "{x: 2, y: 2}"]
    assert later.cmd == ["echo", "set", "sim1/sim", "red", "200"] and not later.enabled
    assert later.trigger is not None and later.trigger.delay == 2.0
    assert plan_of(path, use_red="True").processes[2].enabled
    assert not plan_of(path, use_red="True", red="100").processes[2].enabled


def test_dot_launch_files_are_read_as_xml_or_yaml_by_their_content(write):
    as_xml = write('<?xml version="1.0"?>\n<launch><node pkg="tuilaunch_demos" exec="talker" '
                   'name="x"/></launch>', "old_style.launch")
    as_yaml = write("launch:\n- node: {pkg: tuilaunch_demos, exec: talker, name: y}\n",
                    "other.launch")
    assert [p.full_name for p in plan_of(as_xml).processes] == ["/x"]
    assert [p.full_name for p in plan_of(as_yaml).processes] == ["/y"]
