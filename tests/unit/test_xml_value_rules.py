"""Parameter values in XML and YAML: the typing rules of launch's frontends, case by case.

Expectations are what launch_ros hands a node for the same file (its frontend tests check
the same kinds of values); both formats must agree.
"""

from __future__ import annotations

import sys

from ..conftest import plan_of

EXPECTED = {
    "text": "abc",
    "group.sub.int": 3,
    "group.sep_ints": [3, 6, 9],
    "group.list_from_let": [3, 6, 9],
    "group.quoted_from_let": "[3, 6, 9]",
    "group.sep_floats": [3.0, 6.0, 9.0],
    "group.sep_quoted": ["3", "6", "9"],
    "group.sep_double_quoted": ["'3'", "'6'", "'9'"],
    "group.sep_escaped": ["'3'", "'6'", "'9'"],
    "group.sep_backslashes": ["xy", "zw"],
    "group.empty": "",
    "group.str_from_let": "42",
    "group.list_of_str_quoted": ["'3'", "'6'"],
    "group.list_of_str": ["3", "6"],
}

XML = r"""<launch>
  <let name="quoted" value="\'[3, 6, 9]\'"/>
  <let name="numbers" value="[3, 6, 9]"/>
  <let name="answer" value="42"/>
  <node pkg="tuilaunch_demos" exec="talker" name="typed" namespace="rules"
        ros_args="--log-level info --enclave /e">
    <param name="text" value="abc"/>
    <param name="group">
      <param name="sub"><param name="int" value="3"/></param>
      <param name="sep_ints" value="3, 6, 9" value-sep=", "/>
      <param name="list_from_let" value="$(var numbers)"/>
      <param name="quoted_from_let" value="$(var quoted)"/>
      <param name="sep_floats" value="3., 6., 9." value-sep=", "/>
      <param name="sep_quoted" value="'3', '6', '9'" value-sep=", "/>
      <param name="sep_double_quoted" value="&quot;'3'&quot;, &quot;'6'&quot;, &quot;'9'&quot;"
             value-sep=", "/>
      <param name="sep_escaped" value="\'3\', \'6\', \'9\'" value-sep=", "/>
      <param name="sep_backslashes" value="'\xy', '\zw'" value-sep=", "/>
      <param name="empty" value="''"/>
      <param name="str_from_let" value="$(var answer)" type="str"/>
      <param name="list_of_str_quoted" value="'3', '6'" value-sep=", " type="list_of_str"/>
      <param name="list_of_str" value="3, 6" value-sep=", " type="list_of_str"/>
    </param>
  </node>
  <node exec="PYTHON" args="-c 'import sys; print(sys.argv[1:])'" name="py"/>
</launch>
""".replace("PYTHON", sys.executable)

YAML = r"""
launch:
- let: {name: quoted, value: "'[3, 6, 9]'"}
- let: {name: numbers, value: '[3, 6, 9]'}
- let: {name: answer, value: '42'}
- node:
    pkg: tuilaunch_demos
    exec: talker
    name: typed
    namespace: rules
    ros_args: --log-level info --enclave /e
    param:
    - {name: text, value: abc}
    - name: group
      param:
      - name: sub
        param: [{name: int, value: 3}]
      - {name: sep_ints, value: [3, 6, 9]}
      - {name: list_from_let, value: $(var numbers)}
      - {name: quoted_from_let, value: $(var quoted)}
      - {name: sep_floats, value: [3., 6., 9.]}
      - {name: sep_quoted, value: ['3', '6', '9']}
      - {name: sep_double_quoted, value: ["'3'", "'6'", "'9'"]}
      - {name: sep_escaped, value: ["\\'3\\'", "\\'6\\'", "\\'9\\'"]}
      - {name: sep_backslashes, value: ['\xy', '\zw']}
      - {name: empty, value: ''}
      - {name: str_from_let, value: '$(var answer)', type: str}
      - {name: list_of_str_quoted, value: ["'3'", "'6'"], type: list_of_str}
      - {name: list_of_str, value: ['3', '6'], type: list_of_str}
- node:
    exec: PYTHON
    name: py
    args: -c 'import sys; print(sys.argv[1:])'
""".replace("PYTHON", sys.executable)


def check(plan_file) -> None:
    typed, py = plan_of(plan_file).processes
    assert typed.parameters == EXPECTED
    for name, value in EXPECTED.items():  # 3.0 == 3 in Python: the types must match too
        assert type(typed.parameters[name]) is type(value), name
        if isinstance(value, list):
            assert [type(v) for v in typed.parameters[name]] == [type(v) for v in value], name
    ros_args = typed.cmd[typed.cmd.index("--ros-args"):]
    assert ros_args[:5] == ["--ros-args", "--log-level", "info", "--enclave", "/e"]
    assert py.cmd[:3] == [sys.executable, "-c", "import sys; print(sys.argv[1:])"]
    assert py.full_name == "/py"


def test_xml_values_are_typed_as_launch_types_them(write):
    check(write(XML, "rules.launch.xml"))


def test_yaml_values_are_typed_as_launch_types_them(write):
    check(write(YAML, "rules.launch.yaml"))
