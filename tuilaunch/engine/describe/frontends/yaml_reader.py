"""YAML launch files read with pyyaml, every mapping keeping where it was written."""

from __future__ import annotations

from typing import Any

import yaml

from ...errors import DslError, Origin
from .yaml_element import MarkedDict, YamlElement, element_of

_BASE: Any = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml's parser when present


def _loader(path: str) -> Any:
    class Loader(_BASE):
        pass

    def mapping(loader: Any, node: yaml.MappingNode) -> MarkedDict:
        loader.flatten_mapping(node)
        out = MarkedDict()
        out.origin = _origin(path, node.start_mark)
        out.positions = {}
        for key_node, value_node in node.value:
            key = loader.construct_object(key_node, deep=True)
            out[key] = loader.construct_object(value_node, deep=True)
            out.positions[str(key)] = _origin(path, key_node.start_mark)
        return out

    Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, mapping)
    return Loader


def _origin(path: str, mark: Any) -> Origin:
    return Origin(path, mark.line + 1, mark.column + 1)


def read_yaml(text: str, path: str) -> YamlElement:
    """The root entity (`launch:`) of a YAML launch file."""
    try:
        tree = yaml.load(text, Loader=_loader(path))  # a SafeLoader subclass: safe
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = _origin(path, mark) if mark is not None else Origin(path, 1, 1)
        problem = getattr(exc, "problem", None) or str(exc)
        raise DslError(f"not valid YAML: {problem}", where) from None
    if not isinstance(tree, MarkedDict) or len(tree) != 1:
        raise DslError("a YAML launch file has one root key, `launch:`", Origin(path, 1, 1),
                       hint="write launch: followed by a list of actions")
    (tag, body), = tree.items()
    origin = tree.positions[str(tag)]
    if tag != "launch":
        raise DslError(f"the root key is '{tag}', expected 'launch'", origin)
    return element_of("launch", body, origin)
