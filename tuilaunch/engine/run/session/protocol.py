"""The session socket's wire format: one JSON object per line, and Event <-> dict.

JSON escapes every newline inside strings, so a line is always one whole message; a
message longer than MAX_MESSAGE is refused rather than buffered without bound.

Client to server: `{"id": n, "op": ...}` requests: subscribe {max_lines, interval: the
  most output lines per batch and the least seconds between batches, for a display that
  cannot show more; kinds?: only events of these kinds; fair?: past max_lines, the lines
  dropped are the loudest process's, not the oldest; only?: the one process whose output
  to send (the others' stays in the log files: see view); plain?: for a display, output as
  it shows it (no colour codes, ROS stamps to the millisecond, sent apart as "stamps":
  [ms, or the difference from the batch's stamp before; null for a line without]) and
  output and dropped events without their time (stamped on arrival); stamps?: false, for a
  plain display not showing them (no time column): its lines' ROS stamps are left out and
  kept for it, the last 50,000, read with the op stamps}, stamps {on: bool, since?: n} ->
  {first, stamps: [as in a batch]}: the ROS stamps of the output lines this plain client
  was sent without them, from its line `since` on (lines count from the subscription's
  first), those still kept (from line `first`); `on`: whether the batches after this reply
  carry them (the reply comes after every batch whose lines it covers), view {only: a
  process id or null for all} changes `only`: an event of kind "view" (process: the new `only`, data
  {offsets: {process: its log file's size}}) then marks in the stream where the switch
  happened, so the client reads from the files what it was not sent, status {resources?: false skips
  the CPU/memory sampling}, find {process},
  start/stop {process}, restart {process, prefix?: a tool run before the command (`gdb -q
  -ex run --args`) until a restart without one, log_level?: `--ros-args --log-level` kept
  across respawns until a restart changes it ("" drops it), terminal?: true gives it a
  terminal until a restart without one}, run_action {action}, shutdown
  {reason}, kill (SIGKILL what is left), apply {arguments}, lifecycle {process}, read_log
  {process, start, end, skip, limit, tail}: a process's log file read by the server, for a
  client on another machine (`logs HOST:NAME`, the TUI's replay and what it missed while its
  link was down): the lines from byte `start` to `end` (default: the file's size) after the
  first `skip`, the first `limit` (or with `tail` the last), as `{"lines": [[time, stream,
  text]...], "next": byte to ask again from, "size": the file's size, "skipped": lines left
  out}`; to a
  machine's share of a placed launch (run/machines/machines_share.py): external_event {process, on:
  start|exit, pid, code},
  share_lines {process, start, end, skip}.
  Resources (run/resource_watch.py): `status` gives each process `cpu_percent` (% of one
  core), `rss_bytes` and `threads` over its process tree (None when not running);
  watch_resources {on: bool, processes?: [id] | null} -> {}: while any client watches,
  each watcher gets once a second an event of kind "resources", data {process:
  {cpu_percent, rss_bytes, threads, growing}} (whole percents, memory to 64 KiB: what a
  display shows), with only the figures that changed since the watcher's last event (all
  in its first; a process that stopped once, with None figures). `processes`: the ones
  whose figures the client shows (null or absent: all); of the others only `growing` is
  sent, and figures sent before are taken back once (None). Asked again with other
  `processes`, the watcher is sent the figures it now lacks at once. trend?: [id]: the
  processes whose last minutes the client draws -> {history: {process: [[cpu_percent,
  rss_bytes], ...]: a sample a second, oldest first, 5 minutes at most, kept while some
  client watches}}, then an event "trend", data {process: [cpu_percent, rss_bytes]} each
  second.
  The ROS inspector (engine/ros/inspector.py; a node is a full name or a process id):
  topics {node?, problems_only?: only the topics with QoS problems} -> {"topics": [{name,
  types, publishers: [{node, in_launch, process,
  qos}], subscribers, qos_problems: [sentence]}]};
  watch_qos {on: bool} -> {}: while any client watches, the server checks the graph every
  5 s and each watcher gets an event "qos", data {topics: what topics {problems_only}
  gives}, when they differ from what it was last sent (the first at once);
  hz {topic, window: s} -> {topic, rate_hz, bytes_per_s, messages, window_s} after window s;
  hz_watch {topic, messages?: N (default 10000), every?: s (default 1)} -> {}: events "hz",
  data {topic, rate_hz, min_s, max_s, std_dev_s, window, messages, bytes_per_s, size_mean,
  size_min, size_max, elapsed_s} (ros2 topic hz and bw's figures over the last N messages),
  to this subscribed client every `every` s until it leaves; hz_read {topic} -> that data now;
  watch_rates {topics: [...]} -> {unmeasured: {topic: why}, history: {topic: [rate_hz or
  null, one a second, oldest first: the last 5 minutes some client watched it]}}: this
  client's topics ([]: none);
  the union over clients is measured, and each watcher gets about once a second an event
  "rates", data {topic: {rate_hz, bytes_per_s}} (None until measured);
  echo {topic, count?, max_per_s? (default 5; 0: every message), wait? (s for a publisher,
  at most 5)} -> {}: events "echo", data
  {topic, text: one message's YAML ending in "---"}, to this client until echo_stop {topic}
  or `count` messages (the last has data "done": true); a subscribed client only;
  plot_fields {topic} -> {type, fields: [numeric fields by dotted path, each element of a
  sequence as the last message has them], stamped}; plot {topic, fields: [dotted paths],
  raw?: bool, tag?: any, stamp?: bool (times are header.stamp), wait?: s} -> {topic, type,
  fields, numeric, stamped, stamp, points_per_s}: events "plot" to this subscribed client
  (one stream per topic) until plot_stop {topic}:
  data {topic, tag, t0, points: {field: [[ms, min, max, last], ...]}} (buckets of
  1/points_per_s s; a bucket's time, its last sample's as received, is t0 + ms/1000 in
  seconds of the server's clock), four a second,
  a new stream first sent what the server kept of the topic (5 min at most); with raw,
  data {topic, tag, fields, rows: [[time, value, ...]: every message], dropped: rows left
  out for a link too slow}, ten a second (engine/ros/plot/streams.py);
  params_dump {node} -> {yaml}; params_load {node, yaml, source?: its file name for
  messages} -> {results: [{name, ok, reason}]};
  log_level {node, level} -> {ok: true}, or an error saying the node has no logger service
  and that restarting it with --log-level applies the level.
  A client's streams (echo, rates, resources) end when it disconnects.
  typing {process, on: bool} takes or gives back the keyboard (one client at a time; a
  client that disconnects gives it back), input {process, data: UTF-8 text with control
  characters, "\r" for Enter, "\u0003" for ctrl+c} from the client holding it -> {} or
  {"dropped": bytes the node did not read in time}.
  status -> per process also `command` (argv), `command_line` (paste-ready: cd, env
  changes, argv quoted), `env` (changes to the launcher's environment), and for a death by a
  signal nobody asked for (state "failed") `signal` ("SIGSEGV") and `core` when one was
  kept; `typing` {client, process} or null.
Server to client: `{"type": "hello", "info": {...}}` unasked on connect (its info has
  "protocol", PROTOCOL_VERSION, and "tuilaunch", the version: see check_hello); `{"type": "reply",
  "id": n, "ok": bool, "result"|"error": ...}`; after subscribe, `{"type": "events", "events":
  [...], "states": {process: state}} (the states that changed since this client's last
  batch; left out when none did)` (a relaunch is an event of kind "relaunched" whose
  lines are the new `name:=value` arguments; an event of kind "typing" says who holds the
  keyboard: process, data {"client": id or null}; an "exited" event's data has "signal"
  and "core" for a crash, and "again": true when a restart or a relaunch stopped it to
  start it again (the subscribe reply's "coming_back" lists those between their stop and
  their start); event times are to the millisecond; consecutive output of one
  process is one event; an event "dropped" {process, code: a count} comes first in its
  batch and stands for that process's next `code` lines, which were not sent: a client
  finds them with read_log {start: the process's offset at its subscription, skip: the
  lines of it sent and dropped since}); `{"type": "ended", "status": n}` last.
  The Services and Params tabs (engine/ros/graph_requests.py): nodes, services,
  service_fields {type}, call_service {service, type, request, timeout?}, params_describe
  {node}, params_set {node, values}, params_get {node, names}.
  Without the launch file (engine/run/session/plan_ops.py): plan -> {plan: Plan.to_json(),
  arguments}; preview {arguments, running?} -> {arguments, plan, keep, stop, start,
  error: null} or {arguments, error}: what `apply` with those values would do.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
from typing import Any

from .... import __version__
from ..events import Dropped, Event, ExitCause, Output, ProcessExited, event_of
from .session_dir import SessionError

MAX_MESSAGE = 64 << 20

MESSAGE_TEXT = 8 << 20
"""Output text one message carries at most (an event batch, a read_log answer), but for a
single longer line, itself at most process/output.py's MAX_LINE (8 MiB): JSON escapes a
character into at most six bytes, so a message stays below MAX_MESSAGE, past which the
other side refuses to read."""

PROTOCOL_VERSION = 2
"""The session protocol's version, in every hello and `status` (`version_fields`). Raise
it when a message changes meaning: a detached session outlives an upgrade, and `HOST:NAME`
runs whatever tuilaunch the other machine has, so client and server must speak the same.
1 is the protocol before versions: a hello without "protocol" (tuilaunch 0.1.0's first
releases) counts as 1, a server of those days as too old, never as a match."""

UNVERSIONED = 1
"""What a hello without a "protocol" field speaks: the protocol before it had versions."""

TEST_PROTOCOL_ENV = "TUILAUNCH_TEST_PROTOCOL"
"""For the tests only: a session server started with this set advertises that protocol
version instead of its own ("none": no version at all, as a server from before versions
did), so a real server of another version can be had without another tuilaunch."""

_EVENT_FIELDS = {f.name for f in dataclasses.fields(Event)}


class ProtocolError(Exception):
    """A peer sent something that is not a message of this protocol."""


class VersionMismatch(SessionError):
    """A client and a session server of different protocol versions: one line naming both."""


def version_fields() -> dict[str, Any]:
    """What a server says of its version, in its hello's info and its status."""
    advertised = os.environ.get(TEST_PROTOCOL_ENV)
    if advertised == "none":
        return {}
    return {"protocol": PROTOCOL_VERSION if advertised is None else int(advertised),
            "tuilaunch": __version__}


def greet(line: bytes, session: str) -> dict[str, Any]:
    """The one check of a server's greeting, for every client (the CLI's Link, the TUI's
    connection, an ssh link, `__ls`): its first line, read whole, as its info when it
    speaks this client's protocol; else VersionMismatch saying both versions, or
    SessionError "did not greet" (nothing, or not a hello), or ProtocolError (not JSON: not
    a tuilaunch at all). `session` names it as the user wrote it (NAME or HOST:NAME)."""
    if not line.strip():
        raise SessionError(f"session {session} did not greet")
    return check_hello(decode(line), session)


def check_hello(hello: dict[str, Any], session: str) -> dict[str, Any]:
    """A greeting already decoded, checked as `greet` says."""
    if hello.get("type") != "hello" or not isinstance(hello.get("info"), dict):
        raise SessionError(f"session {session} did not greet")
    info: dict[str, Any] = hello["info"]
    theirs = info.get("protocol", UNVERSIONED)
    if theirs != PROTOCOL_VERSION:
        release = info.get("tuilaunch")
        what = f"tuilaunch {release}" if release else "a tuilaunch from before protocol versions"
        raise VersionMismatch(
            f"session {session} speaks protocol {theirs} ({what}), this tuilaunch speaks "
            f"{PROTOCOL_VERSION} ({__version__}): use the same tuilaunch on both sides")
    return info


def encode(message: dict[str, Any]) -> bytes:
    # default=str: a detail that is not JSON (a path, an enum) is sent as its text, never
    # stops the events that follow it
    return json.dumps(message, separators=(",", ":"), default=str).encode() + b"\n"


def decode(line: bytes) -> dict[str, Any]:
    try:
        message = json.loads(line)
    except ValueError as exc:
        raise ProtocolError(f"not a JSON message: {exc}") from None
    if not isinstance(message, dict):
        raise ProtocolError("a message must be a JSON object")
    return message


def event_to_dict(event: Event, display: bool = False) -> dict[str, Any]:
    # defaults are left out: an output batch is then mostly its lines; the time to the
    # millisecond (what the log files keep), as sub-millisecond digits are noise that no
    # compression squeezes over an ssh link. `display`: for a screen, which stamps output
    # on arrival and shows no time of its own for a count of lines not sent
    data: dict[str, Any] = {"kind": event.kind}
    output = isinstance(event, Output)
    if not (display and isinstance(event, (Output, Dropped))):
        data["time"] = round(event.time, 3)
    for name in ("process", "pid", "stream", "code", "reason"):
        value = getattr(event, name)
        if value is None or (output and (name == "pid" or value == "stdout")):
            continue  # output: its pid is the started event's; stdout is the default stream
        if name == "reason" and isinstance(event, Dropped):
            continue  # the count says it; the sentence is the client's to write
        data[name] = value
    if event.lines:
        data["lines"] = event.lines
    if event.level != "INFO":
        data["level"] = event.level
    if event.data is not None:
        data["data"] = event.data  # a component's result, a lifecycle state, a stop asked
    return data


_STAMPED = re.compile(r"^(\[[A-Z]+\] )\[(\d+)\.(\d{3})\] ")


class Stamps:
    """A display's batch carries each output line's ROS stamp (already to the millisecond,
    as shown) as a number apart from the line, the difference in ms from the stamp before
    it in the batch: the digits that change from line to line are what a compressing
    link cannot squeeze. One per batch on each side, in the batch's order (and one per
    answer to the op `stamps`)."""

    def __init__(self) -> None:
        self.last: int | None = None

    @staticmethod
    def take(data: dict[str, Any]) -> list[int | None]:
        """An output event's dict: its stamped lines lose their stamp, returned (ms, None
        for a line without) one per line."""
        lines: list[str] = []
        stamps: list[int | None] = []
        for line in data.get("lines") or []:
            match = _STAMPED.match(line)
            if match is None:
                lines.append(line)
                stamps.append(None)
                continue
            stamps.append(int(match.group(2)) * 1000 + int(match.group(3)))
            lines.append(match.group(1) + line[match.end():])
        data["lines"] = lines
        return stamps

    def encode(self, stamps: list[int | None]) -> list[int | None]:
        steps: list[int | None] = []
        for ms in stamps:
            steps.append(None if ms is None else ms if self.last is None else ms - self.last)
            if ms is not None:
                self.last = ms
        return steps

    def decode(self, steps: list[Any]) -> list[int | None]:
        stamps: list[int | None] = []
        for step in steps:
            if not isinstance(step, int):
                stamps.append(None)
                continue
            self.last = step if self.last is None else self.last + step
            stamps.append(self.last)
        return stamps

    def pack(self, data: dict[str, Any]) -> list[int | None]:
        """An output event's dict: its stamped lines lose their stamp to `stamps`; the
        stamps themselves (ms) returned, one per line."""
        stamps = self.take(data)
        if any(ms is not None for ms in stamps):
            data["stamps"] = self.encode(stamps)
        return stamps

    def unpack(self, data: dict[str, Any]) -> None:
        steps = data.pop("stamps", None)
        if not isinstance(steps, list):
            return
        given = data.get("lines") or []
        stamps = self.decode(steps) + [None] * (len(given) - len(steps))
        # zip(strict=False): a line is never lost to a short list
        data["lines"] = [line if ms is None else with_stamp(line, ms)
                         for line, ms in zip(given, stamps, strict=False)]


def with_stamp(line: str, ms: int) -> str:
    """A line sent without its ROS stamp (`[INFO] [logger]: ...`) as it was printed, with
    the stamp to the millisecond after its level."""
    level = line.index("] ") + 2
    return f"{line[:level]}[{ms // 1000}.{ms % 1000:03d}] {line[level:]}"


def event_from_dict(data: dict[str, Any]) -> Event:
    """An event back from its dict: a process's end as a ProcessExited, its cause read from
    its data ("requested", "typed") as it was decided where the process ended."""
    fields = {k: v for k, v in data.items() if k in _EVENT_FIELDS}
    if not isinstance(fields.get("kind"), str):
        raise ProtocolError(f"an event without a kind: {data!r}")
    kind = fields.pop("kind")
    if kind == "exited":
        said = fields.get("data") or {}
        cause = ExitCause.of(int(fields.get("code") or 0), bool(said.get("requested")),
                             bool(said.get("typed")))
        return ProcessExited(**fields, cause=cause)
    return event_of(kind, **fields)
