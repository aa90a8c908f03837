"""`--machines MACHINES.yaml`: which machines there are, and which processes run where.

```yaml
machines:
  nuc:
    host: robot1-nuc                      # anything ssh accepts
    tuilaunch: /opt/venv/bin/tuilaunch    # optional (default: tuilaunch)
    setup: /opt/ros/jazzy/setup.bash      # optional, sourced first
    env: {RMW_IMPLEMENTATION: rmw_fastrtps_cpp}   # optional
placement:
  - match: /far/**      # a full node name glob, or a process id (glob)
    machine: nuc
```

A `match` starting with '/' is a glob on full node names: `*` is any run of characters
within one name segment, `**` any number of segments (`/far/**` is everything under /far,
`/**/camera` every node named camera), `?` one character. Otherwise it is a glob on process
ids (`camera-*`). The first rule that matches places a process; the rest stay here.
Placement is plain data: the launch file is not changed by it.

Each mistake is one line naming the file, the line and the field (from yaml's marks).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:  # pyyaml is imported where a machines file is read, not by every launch
    import yaml

from ..errors import LaunchError, Origin
from .model import Plan

_MACHINE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
_ENV_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_HOST = re.compile(r"^[A-Za-z0-9_.%+@:\[\]-]+$")


class MachinesError(LaunchError):
    """A machines file that cannot be used."""


@dataclass(frozen=True)
class Machine:
    name: str
    host: str
    tuilaunch: str | None = None
    """The tuilaunch command there (None: TUILAUNCH_REMOTE, else `tuilaunch`)."""
    setup: str | None = None
    """A shell file sourced there before tuilaunch runs (roslaunch's env-loader)."""
    env: Mapping[str, str] = field(default_factory=dict)
    origin: Origin | None = None


@dataclass(frozen=True)
class Rule:
    match: str
    machine: str
    origin: Origin | None = None

    def matches(self, process_id: str, full_name: str | None) -> bool:
        if self.match.startswith("/"):
            return full_name is not None and _glob(self.match).fullmatch(full_name) is not None
        return _glob(self.match).fullmatch(process_id) is not None


@dataclass(frozen=True)
class Machines:
    machines: dict[str, Machine]
    rules: list[Rule]
    path: str = ""


class Placeable(Protocol):
    """What placement looks at: a plan's process (ProcessPlan has both)."""

    @property
    def id(self) -> str: ...

    @property
    def full_name(self) -> str | None: ...


@dataclass(frozen=True)
class Placement:
    """`--machines` as a launch carries it: the machines, the file's text (sent as is to
    the other machines, whose shares place the same way), and the machine whose share this
    side runs (`--share`; None: the launching side)."""

    machines: Machines
    text: str
    share: str | None = None

    def apply(self, plan: Plan) -> Plan:
        """Sets each process's `machine` (same plan, changed in place and returned); a rule
        that places nothing is a warning of the plan."""
        placed = place(plan.processes, self.machines)
        for proc in plan.processes:
            proc.machine = placed[proc.id]
        unused = unused_rules(plan.processes, self.machines)
        for rule in unused:
            where = f"{rule.origin}: " if rule.origin else ""
            plan.warnings.append(f"{where}placement rule {rule.match!r} -> {rule.machine} "
                                 f"places no process{self_named(rule, plan.processes)}")
        told: set[str] = set()
        for rule in self.machines.rules:
            if rule in unused:
                continue
            # a rule that places others, and would take these by the names they show:
            # they stay here, which is said once per process (the first such rule)
            left = [p for p in _self_named_matching(rule, plan.processes)
                    if p.machine is None and p.id not in told]
            told.update(p.id for p in left)
            if left:
                where = f"{rule.origin}: " if rule.origin else ""
                plan.warnings.append(
                    f"{where}placement rule {rule.match!r} -> {rule.machine} leaves "
                    f"{', '.join(p.id for p in left)} here: {_naming(left)}")
        return plan

    def used(self, plan: Plan) -> list[Machine]:
        """The other machines with a process of the plan to run, in the file's order."""
        names = {p.machine for p in plan.processes if p.enabled and p.machine}
        return [m for name, m in self.machines.machines.items()
                if name in names and name != self.share]


def load_placement(path: str, share: str | None = None) -> Placement:
    """`--machines FILE`: read and checked (MachinesError with file and line)."""
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise MachinesError(f"machines file {path}: {exc.strerror or exc}") from None
    return placement_from_text(text, path, share)


def placement_from_text(text: str, path: str, share: str | None = None) -> Placement:
    machines = parse_machines(text, path)
    if share is not None and share not in machines.machines:
        raise MachinesError(f"--share {share!r} is not among the machines of {path}",
                            hint=f"machines: {', '.join(machines.machines) or 'none'}")
    return Placement(machines, text, share)


def place(processes: Iterable[Placeable], machines: Machines) -> dict[str, str | None]:
    """Each process id -> the machine the first matching rule names, or None (here)."""
    placed: dict[str, str | None] = {}
    for proc in processes:
        placed[proc.id] = next((rule.machine for rule in machines.rules
                                if rule.matches(proc.id, proc.full_name)), None)
    return placed


def self_named(rule: Rule, processes: Iterable[Placeable]) -> str:
    """Why a node-name rule matches nothing when it names nodes that choose their own name
    (shown `/r1/<talker>`: the launch file gives none, so it is known only once the node
    runs), and the process ids that would match them."""
    named = _self_named_matching(rule, processes)
    if not named:
        return ""
    return f": {_naming(named)}"


def _self_named_matching(rule: Rule, processes: Iterable[Placeable]) -> list[Any]:
    """The processes whose node names itself (no full name in the plan) and whose shown
    name (`/r1/<talker>`, brackets taken off) the node-name rule would match."""
    if not rule.match.startswith("/"):
        return []
    return [p for p in processes if p.full_name is None and
            _glob(rule.match).fullmatch(str(getattr(p, "label", "")).replace("<", "")
                                        .replace(">", "")) is not None]


def _naming(named: list[Any]) -> str:
    """Why a node-name rule cannot place these, and what to match instead."""
    labels = ", ".join(str(getattr(p, "label", p.id)) for p in named)
    ids = sorted({re.sub(r"-\d+$", "-*", p.id) for p in named})
    return (f"{labels} name{'s' if len(named) == 1 else ''} itself in its code (the launch "
            f"file gives no name), so a placement rule cannot know it before it runs; match "
            f"its process id instead: {', '.join(repr(i) for i in ids)}")


def unused_rules(processes: Iterable[Placeable], machines: Machines) -> list[Rule]:
    """Rules that place nothing (a typo in a name is then said, not silently ignored)."""
    procs = list(processes)
    return [rule for rule in machines.rules
            if not any(rule.matches(p.id, p.full_name) for p in procs)]


@lru_cache(maxsize=256)
def _glob(pattern: str) -> re.Pattern[str]:
    """`**` spans segments ('/**/' also matches a single '/'), `*` and `?` stay in one."""
    out = []
    i = 0
    while i < len(pattern):
        if pattern.startswith("/**/", i):
            out.append("(?:/|/.*/)")
            i += 4
        elif pattern.startswith("**", i):
            out.append(".*")
            i += 2
        elif pattern[i] == "*":
            out.append("[^/]*")
            i += 1
        elif pattern[i] == "?":
            out.append("[^/]")
            i += 1
        else:
            out.append(re.escape(pattern[i]))
            i += 1
    return re.compile("".join(out))


# --- reading the file ----------------------------------------------------------------------------

def load_machines(path: str | Path) -> Machines:
    path = str(path)
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise MachinesError(f"machines file {path}: {exc.strerror or exc}") from None
    return parse_machines(text, path)


def parse_machines(text: str, path: str = "<machines>") -> Machines:
    import yaml

    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        origin = Origin(path, mark.line + 1, mark.column + 1) if mark is not None else None
        problem = getattr(exc, "problem", None) or str(exc)
        raise MachinesError(f"not YAML: {problem}", origin) from None
    if root is None:
        raise MachinesError(f"machines file {path} is empty",
                            hint="it needs 'machines:' and 'placement:'")
    top = _mapping(root, path, "the file")
    _only(top, path, {"machines", "placement"}, "the file")
    if "machines" not in top:
        raise MachinesError("no 'machines:'", _origin(root, path),
                            hint="machines: {NAME: {host: HOST}}")
    machines: dict[str, Machine] = {}
    for key, node in _mapping(top["machines"][1], path, "machines").items():
        key_node, value = node
        if not _MACHINE_NAME.match(key):
            raise MachinesError(f"machine name {key!r} is not usable", _origin(key_node, path),
                                hint="letters, digits, '_', '.' and '-'")
        machines[key] = _machine(key, value, path)
    rules: list[Rule] = []
    if "placement" in top:
        placement = top["placement"][1]
        if not isinstance(placement, yaml.SequenceNode):
            raise MachinesError("placement: must be a list of {match, machine}",
                                _origin(placement, path))
        for item in placement.value:
            rules.append(_rule(item, path, machines))
    return Machines(machines, rules, path)


def _machine(name: str, node: yaml.Node, path: str) -> Machine:
    where = f"machines.{name}"
    fields = _mapping(node, path, where)
    _only(fields, path, {"host", "tuilaunch", "setup", "env"}, where)
    if "host" not in fields:
        raise MachinesError(f"{where}: no 'host:'", _origin(node, path),
                            hint="host: an alias from ~/.ssh/config, a host name or user@host")
    host = _string(fields["host"][1], path, f"{where}.host")
    if host.startswith("-") or not _HOST.match(host):
        raise MachinesError(f"{where}.host {host!r} is not a host", _origin(
            fields["host"][1], path), hint="an alias from ~/.ssh/config, a host or user@host")
    tuilaunch = _string(fields["tuilaunch"][1], path, f"{where}.tuilaunch") \
        if "tuilaunch" in fields else None
    setup = _string(fields["setup"][1], path, f"{where}.setup") if "setup" in fields else None
    env: dict[str, str] = {}
    if "env" in fields:
        for key, (key_node, value) in _mapping(fields["env"][1], path, f"{where}.env").items():
            if not _ENV_NAME.match(key):
                raise MachinesError(f"{where}.env: {key!r} is not a variable name",
                                    _origin(key_node, path))
            env[key] = _string(value, path, f"{where}.env.{key}")
    return Machine(name, host, tuilaunch, setup, env, _origin(node, path))


def _rule(node: yaml.Node, path: str, machines: dict[str, Machine]) -> Rule:
    fields = _mapping(node, path, "placement item")
    _only(fields, path, {"match", "machine"}, "placement item")
    for required in ("match", "machine"):
        if required not in fields:
            raise MachinesError(f"placement item: no '{required}:'", _origin(node, path),
                                hint="- {match: /ns/**, machine: NAME}")
    match = _string(fields["match"][1], path, "placement.match")
    if not match:
        raise MachinesError("placement.match is empty", _origin(fields["match"][1], path))
    machine = _string(fields["machine"][1], path, "placement.machine")
    if machine not in machines:
        known = ", ".join(machines) or "none"
        raise MachinesError(f"placement.machine {machine!r} is not among the machines",
                            _origin(fields["machine"][1], path), hint=f"machines: {known}")
    return Rule(match, machine, _origin(node, path))


def _origin(node: yaml.Node, path: str) -> Origin:
    return Origin(path, node.start_mark.line + 1, node.start_mark.column + 1)


def _mapping(node: yaml.Node, path: str, where: str) -> dict[str, tuple[yaml.Node, yaml.Node]]:
    """A mapping's keys (strings, each once) -> (key node, value node)."""
    import yaml

    if not isinstance(node, yaml.MappingNode):
        raise MachinesError(f"{where} must be a mapping", _origin(node, path))
    out: dict[str, tuple[yaml.Node, yaml.Node]] = {}
    for key_node, value in node.value:
        if not isinstance(key_node, yaml.ScalarNode):
            raise MachinesError(f"{where}: a key must be a name", _origin(key_node, path))
        key = str(key_node.value)
        if key in out:
            raise MachinesError(f"{where}: {key!r} is given twice", _origin(key_node, path))
        out[key] = (key_node, value)
    return out


def _only(fields: Mapping[str, tuple[yaml.Node, yaml.Node]], path: str, known: set[str],
          where: str) -> None:
    for key, (key_node, _) in fields.items():
        if key not in known:
            raise MachinesError(f"{where}: unknown field {key!r}", _origin(key_node, path),
                                hint=f"known: {', '.join(sorted(known))}")


def _string(node: yaml.Node, path: str, where: str) -> str:
    """A scalar as the text written (`5` and `true` stay "5" and "true": env values)."""
    import yaml

    if not isinstance(node, yaml.ScalarNode) or node.tag == "tag:yaml.org,2002:null":
        raise MachinesError(f"{where} must be a single value", _origin(node, path))
    return str(node.value)
