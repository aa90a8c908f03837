"""Load and resolve the same bringup written in Python, XML and YAML, side by side.

Each file has N nodes in nested groups with pushed namespaces, a condition, typed parameters
and a remapping. Prints load and resolve times per format and each format's ratio to Python,
measured in one run.

    python bench/frontend_bench.py
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

SIZES = (100, 1000)
ROUNDS = 5


def python_text(nodes: int) -> str:
    body = []
    for i in range(nodes):
        body.append(
            f"        GroupAction([PushRosNamespace('robot{i // 10}'), Node(package="
            f"'tuilaunch_demos', executable='talker', name='n{i}', condition=IfCondition("
            f"V('extra')), parameters=[{{'rate': V('rate'), 'message': 'm{i}', 'gains': "
            f"[1.0, 2.0]}}], remappings=[('chatter', 'out')])]),")
    return ("from launch import LaunchDescription\n"
            "from launch.actions import DeclareLaunchArgument, GroupAction\n"
            "from launch.conditions import IfCondition\n"
            "from launch.substitutions import LaunchConfiguration as V\n"
            "from launch_ros.actions import Node, PushRosNamespace\n"
            "def generate_launch_description():\n"
            "    return LaunchDescription([\n"
            "        DeclareLaunchArgument('rate', default_value='2.0'),\n"
            "        DeclareLaunchArgument('extra', default_value='true'),\n"
            + "\n".join(body) + "\n    ])\n")


def xml_text(nodes: int) -> str:
    body = [f"""  <group>
    <push-ros-namespace namespace="robot{i // 10}"/>
    <node pkg="tuilaunch_demos" exec="talker" name="n{i}" if="$(var extra)">
      <param name="rate" value="$(var rate)"/>
      <param name="message" value="m{i}"/>
      <param name="gains" value="[1.0, 2.0]"/>
      <remap from="chatter" to="out"/>
    </node>
  </group>""" for i in range(nodes)]
    return ('<launch>\n  <arg name="rate" default="2.0"/>\n  <arg name="extra" default="true"/>\n'
            + "\n".join(body) + "\n</launch>\n")


def yaml_text(nodes: int) -> str:
    body = [f"""- group:
  - push-ros-namespace: {{namespace: robot{i // 10}}}
  - node:
      pkg: tuilaunch_demos
      exec: talker
      name: n{i}
      if: $(var extra)
      param:
      - {{name: rate, value: $(var rate)}}
      - {{name: message, value: m{i}}}
      - {{name: gains, value: [1.0, 2.0]}}
      remap:
      - {{from: chatter, to: out}}""" for i in range(nodes)]
    return ("launch:\n- arg: {name: rate, default: '2.0'}\n- arg: {name: extra, default: 'true'}\n"
            + "\n".join(body) + "\n")


def measure(path: Path, nodes: int) -> tuple[float, float]:
    from tuilaunch.engine import load_file, resolve

    loads, resolves = [], []
    for _ in range(ROUNDS):
        start = time.perf_counter()
        loaded = load_file(str(path))
        loaded_at = time.perf_counter()
        plan = resolve(loaded, {"rate": "5"})
        resolves.append(time.perf_counter() - loaded_at)
        loads.append(loaded_at - start)
        assert len(plan.enabled_processes()) == nodes
        assert plan.processes[0].parameters == {"rate": 5, "message": "m0", "gains": [1.0, 2.0]}
    return statistics.median(loads), statistics.median(resolves)


def main() -> None:
    from tuilaunch.engine.packages import ensure_environment

    ensure_environment()
    print(f"{'nodes':>6} {'format':>7} {'load s':>8} {'resolve s':>10} {'load vs py':>11}")
    with tempfile.TemporaryDirectory() as folder:
        for nodes in SIZES:
            files = {"python": ("gen.launch.py", python_text(nodes)),
                     "xml": ("gen.launch.xml", xml_text(nodes)),
                     "yaml": ("gen.launch.yaml", yaml_text(nodes))}
            results = {}
            for kind, (name, text) in files.items():
                path = Path(folder) / f"{nodes}_{name}"
                path.write_text(text)
                results[kind] = measure(path, nodes)
            for kind, (load, resolved) in results.items():
                ratio = load / results["python"][0]
                print(f"{nodes:>6} {kind:>7} {load:>8.3f} {resolved:>10.3f} {ratio:>10.2f}x")


if __name__ == "__main__":
    main()
