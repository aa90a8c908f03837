"""A node's live parameters as a params file a launch file loads, and a file loaded back."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
import yaml

from tuilaunch.engine.errors import LaunchError
from tuilaunch.engine.plan.components import file_parameters
from tuilaunch.engine.ros.bridge import RosBridge, RosError
from tuilaunch.engine.ros.param_files import file_values, nested

from .inspector_helpers import eventually, ros_nodes, run

NODE = "/params_test/lidar"
PARAM_NODE = ["lidar", "--namespace", "/params_test", "--params"]


async def ready(bridge: RosBridge) -> None:
    async def check() -> bool:
        return "/params_test/lidar/list_parameters" in dict(await bridge.list_services())
    await eventually(check, 60, "the parameter services")


def test_dump_is_a_launch_params_file_with_dotted_names_nested(tmp_path: Path):
    async def scenario(bridge: RosBridge) -> str:
        await ready(bridge)
        return await bridge.dump_params(NODE)

    with ros_nodes(PARAM_NODE):
        text = run(scenario)
    document = yaml.safe_load(text)
    values = document[NODE]["ros__parameters"]
    assert values["gains"] == {"i": 0.25, "p": 1.5}
    assert values["limits"] == {"speed": {"max": 2}}
    assert values["frames"] == ["base", "laser"]
    assert values["label"] == "lidar" and values["enabled"] is True
    assert values["use_sim_time"] is False
    path = tmp_path / "lidar.yaml"
    path.write_text(text)
    # what launch gives the node from this file: the same values, flat
    loaded = file_parameters(str(path), "params_test/lidar", None)
    assert loaded["gains.p"] == 1.5 and loaded["limits.speed.max"] == 2
    assert loaded["rate"] == 10.0


def test_dump_edit_load_round_trip_with_the_nodes_answer(tmp_path: Path):
    async def scenario(bridge: RosBridge) -> tuple[Any, ...]:
        await ready(bridge)
        document = yaml.safe_load(await bridge.dump_params(NODE))
        values = document[NODE]["ros__parameters"]
        values["gains"]["p"] = 3.0
        values["label"] = "front_lidar"
        edited = tmp_path / "edited.yaml"
        edited.write_text(yaml.safe_dump(document))
        results = await bridge.load_params(NODE, str(edited))
        after = await bridge.get_parameters(NODE, ["gains.p", "label", "rate"])
        wildcard = tmp_path / "wildcard.yaml"
        wildcard.write_text("/**:\n  ros__parameters:\n    rate: 5.0\n"
                            "params_test:\n  lidar:\n    ros__parameters:\n"
                            "      gains: {i: 0.5}\n      enabled: not-a-bool\n"
                            "      undeclared: 1\n")
        refused = await bridge.load_params(NODE, str(wildcard))
        final = await bridge.get_parameters(NODE, ["rate", "gains.i", "enabled"])
        return results, after, refused, final

    with ros_nodes(PARAM_NODE):
        results, after, refused, final = run(scenario)
    assert all(r.successful for r in results) and len(results) >= 7
    # read-only at run time, and the same value: not sent, said so
    (read_only,) = [r for r in results if r.name == "start_type_description_service"]
    assert read_only.reason == "read-only, unchanged"
    assert after == {"gains.p": 3.0, "label": "front_lidar", "rate": 10.0}
    answers = {r.name: r for r in refused}
    assert answers["rate"].successful and answers["gains.i"].successful
    assert not answers["enabled"].successful and answers["enabled"].reason
    assert not answers["undeclared"].successful  # the node does not take unknown names
    assert final == {"rate": 5.0, "gains.i": 0.5, "enabled": True}


def test_a_file_without_a_section_for_the_node_says_which_it_has(tmp_path: Path):
    path = tmp_path / "other.yaml"
    path.write_text("/other/node:\n  ros__parameters:\n    a: 1\n")
    with pytest.raises(LaunchError, match=r"no section for /params_test/lidar "
                                          r"\(it has: /other/node\)"):
        file_values(str(path), NODE)
    path.write_text("a: [1\n")
    with pytest.raises(LaunchError, match="is not valid YAML"):
        file_values(str(path), NODE)


def test_nesting():
    assert nested({"a.b.c": 1, "a.b.d": 2, "e": 3}) == {"a": {"b": {"c": 1, "d": 2}}, "e": 3}


def test_a_node_that_does_not_answer_is_one_line():
    async def scenario(bridge: RosBridge) -> str:
        return await bridge.dump_params("/params_test/nobody", timeout=1.0)

    with pytest.raises(RosError) as caught:
        run(scenario)
    assert str(caught.value) == "service /params_test/nobody/list_parameters is not available"
