"""A node's live parameters as a params YAML file a launch file loads as is, and such a file
loaded into a running node.

The file's shape is `ros2 param dump`'s: `/ns/node: {ros__parameters: {...}}`, dotted
names nested (`a.b.c: 1` as `a: {b: {c: 1}}`). Loading takes the sections launch would give
that node: `/**` (and `**`), then the node's own key, written `/ns/node`, `ns/node` or
nested as `ns: {node: ...}`; later sections win.
"""

from __future__ import annotations

from typing import Any

import yaml

from ..describe.parameter_files import dotted, node_sections
from ..errors import LaunchError
from .calls import BridgeCalls, SetResult


def nested(values: dict[str, Any]) -> dict[str, Any]:
    """`{"a.b": 1, "a.c": 2}` as `{"a": {"b": 1, "c": 2}}` (keys sorted, as dump sorts)."""
    tree: dict[str, Any] = {}
    for name in sorted(values):
        *parents, leaf = name.split(".")
        level = tree
        for part in parents:
            child = level.setdefault(part, {})
            if not isinstance(child, dict):  # `a` and `a.b` both set: keep `a` as a key
                level = {}
                break
            level = child
        level[leaf] = values[name]
    return tree


def params_yaml(node: str, values: dict[str, Any]) -> str:
    """The file text for `node` (a full name, `/ns/name`)."""
    values = {k: v for k, v in values.items() if v is not None}  # unset: nothing to write
    document = {node: {"ros__parameters": nested(values)}}
    return yaml.safe_dump(document, default_flow_style=False, sort_keys=False,
                          allow_unicode=True)


async def dump(bridge: BridgeCalls, node: str, timeout: float = 5.0) -> str:
    names = await bridge.list_parameters(node, timeout)
    values = await bridge.get_parameters(node, names, timeout)
    return params_yaml(node, values)


def file_values(path: str, node: str) -> dict[str, Any]:
    """The parameters a params file gives `node` (full name), flat (`a.b.c`)."""
    try:
        with open(path, encoding="utf-8") as handle:
            text = handle.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise LaunchError(f"parameter file {path} cannot be read: "
                          f"{getattr(exc, 'strerror', None) or exc}") from None
    return text_values(text, node, path)


def text_values(text: str, node: str, path: str) -> dict[str, Any]:
    """As `file_values`, for a file's text (sent by a session client); `path` names it in
    messages."""
    try:
        loaded = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f":{mark.line + 1}" if mark is not None else ""
        raise LaunchError(f"parameter file {path}{where} is not valid YAML") from None
    if not isinstance(loaded, dict):
        raise LaunchError(f"parameter file {path} does not hold a mapping")
    found = node_sections(loaded)
    if not found:
        raise LaunchError(f"parameter file {path} has no ros__parameters section")
    own = node.strip("/")
    values: dict[str, Any] = {}
    for key in ("**", own):
        if key in found:
            values.update(dotted(found[key]))
    if not values and not any(k in found for k in ("**", own)):
        raise LaunchError(f"parameter file {path} has no section for {node} "
                          f"(it has: {', '.join('/' + k for k in sorted(found))})")
    return values


async def load(bridge: BridgeCalls, node: str, path: str, timeout: float = 5.0)\
        -> list[SetResult]:
    """Sets every parameter the file at `path` gives the node (see `load_values`)."""
    return await load_values(bridge, node, file_values(path, node), timeout)


async def load_values(bridge: BridgeCalls, node: str, values: dict[str, Any],
                      timeout: float = 5.0) -> list[SetResult]:
    """Sets every parameter the file gives the node; the node's answer per parameter.

    A read-only parameter (set at start only, like `start_type_description_service`) that
    already holds the file's value is not sent, so that loading a dump of the same node is
    clean; it is answered as successful, "read-only, unchanged". With another value the node
    refuses it, and says so."""
    if not values:
        return []
    described = {d.name: d for d in await bridge.describe_parameters(node, list(values),
                                                                     timeout)}
    unchanged = [name for name, value in values.items()
                 if name in described and described[name].read_only
                 and described[name].value == value]
    to_set = {name: value for name, value in values.items() if name not in unchanged}
    answers = {r.name: r for r in (await bridge.set_parameters(node, to_set, timeout)
                                   if to_set else [])}
    for name in unchanged:
        answers[name] = SetResult(name, True, "read-only, unchanged")
    return [answers[name] for name in values if name in answers]
