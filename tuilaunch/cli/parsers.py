"""The command line's two parsers: the launcher's (`tuilaunch FILE name:=value`) and the
session commands' (`tuilaunch ls | attach | ...`).

Kept apart from the commands themselves and importing nothing but argparse: shell completion
builds them on every Tab press, before any of the engine is loaded (completion.py)."""

from __future__ import annotations

import argparse

COMMANDS = ("ls", "attach", "stop", "start", "status", "logs", "restart", "wait", "topics", "hz",
            "echo", "plot", "params", "log-level", "completion", "serve", "record")
PROCESS_STATES = ("pending", "running", "stopping", "exited", "failed", "respawning", "skipped",
                  "done", "cancelled")
LIFECYCLE_STATES = ("unconfigured", "inactive", "active", "finalized")
LEVELS = ("DEBUG", "INFO", "WARN", "ERROR", "FATAL")
"""The ROS levels, lowest first (as tui/output_store.py ranks a line)."""
NODE_LEVELS = ("debug", "info", "warn", "error", "fatal", "unset")
"""What `log-level` sets a node's logger to."""
SHELLS = ("bash", "zsh")
TABS = ("nodes", "args", "services", "params", "topics")
"""The TUI's tabs, as keys 1-5 show them."""
HZ_WINDOW = 10000
"""`hz -w`'s default, as ros2 topic hz's: the rate is taken over the last N messages."""


def version() -> str:
    """The installed distribution's version (pyproject.toml's), else the package's own."""
    from importlib import metadata

    try:
        return metadata.version("tuilaunch")
    except metadata.PackageNotFoundError:
        from .. import __version__

        return __version__


class _Version(argparse.Action):
    """`--version`, looked up only when asked (not on every Tab press)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: object, option_string: str | None = None) -> None:
        print(f"tuilaunch {version()}")
        parser.exit()


def launch_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tuilaunch",
        description="Run a ROS 2 launch file (SimpleLauncher DSL, launch API, XML or YAML) in "
        "a terminal UI.",
        epilog="Arguments are given as name:=value, as with ros2 launch.")
    parser.add_argument("items", nargs="+", metavar="FILE | PACKAGE FILE | name:=value",
                        help="a launch file, or a package and a launch file in its share, "
                        "then launch arguments")
    parser.add_argument("--version", action=_Version, nargs=0,
                        help="print tuilaunch's version and exit")
    # ros2 launch's spellings too (-d, -n, --print-description, --show-arguments): a ROS
    # user's fingers type them
    parser.add_argument("-s", "--show-args", "--show-arguments", action="store_true",
                        help="list the launch arguments and exit")
    parser.add_argument("-p", "--print", "--print-description", dest="print_plan",
                        action="store_true",
                        help="print what would run with these arguments and exit")
    parser.add_argument("--json", action="store_true", help="with --print: one JSON object")
    parser.add_argument("--headless", "-n", "--noninteractive", action="store_true",
                        help="run without the TUI, printing each line as [process-id] line "
                        "(the default when not in a terminal)")
    parser.add_argument("--scrollback", type=int, default=5000, metavar="LINES",
                        help="TUI: lines kept per node's pane (log files keep all; "
                        "default 5000)")
    parser.add_argument("--detach", action="store_true",
                        help="start the launch as a background session, print its name, and "
                        "exit (tuilaunch attach NAME opens it)")
    parser.add_argument("--name", metavar="NAME",
                        help="the session's name (default: the file's stem and a number)")
    parser.add_argument("--on", metavar="HOST",
                        help="start the launch on HOST (over ssh; its file and packages are "
                        "HOST's) as a session, then attach to it (--detach: only start)")
    parser.add_argument("--keep-on-hangup", action="store_true",
                        help="TUI: a dropped terminal (SIGHUP) detaches instead of stopping "
                        "the launch")
    parser.add_argument("--machines", metavar="MACHINES.yaml",
                        help="run each node on the machine this file places it on (over "
                        "ssh); with --print, show where each runs")
    # how the launching side starts another machine's share of the launch (machines_share)
    parser.add_argument("--share", metavar="MACHINE", help=argparse.SUPPRESS)
    parser.add_argument("--machines-text", metavar="YAML", help=argparse.SUPPRESS)
    parser.add_argument("--launch-prefix", metavar="CMD",
                        help="as ros2 launch: put CMD (e.g. 'gdb -ex run --args') before "
                        "each executable without a prefix of its own (launch-prefix:=CMD)")
    parser.add_argument("--launch-prefix-filter", metavar="REGEX",
                        help="as ros2 launch: only executables whose name REGEX matches from "
                        "its start get --launch-prefix (launch-prefix-filter:=REGEX)")
    parser.add_argument("-a", "--show-all-subprocesses-output", action="store_true",
                        help="as ros2 launch: print every process's output whatever its "
                        "output= says (OVERRIDE_LAUNCH_PROCESS_OUTPUT=both)")
    parser.add_argument("--black-box", type=float, metavar="SECONDS",
                        help="keep the last SECONDS of every topic and line in memory, "
                        "written as MCAP into the log folder when a process dies unasked")
    parser.add_argument("--black-box-size", type=float, default=BLACK_BOX_SIZE, metavar="MB",
                        help=f"the black box's bound in memory, the oldest dropped first "
                        f"(default {BLACK_BOX_SIZE} MB)")
    parser.add_argument("-d", "--debug", action="store_true", help="tracebacks for errors")
    parser.epilog = (parser.epilog or "") + (
        "  Sessions: tuilaunch ls | attach [NAME] | stop NAME [PROCESS ...] | start NAME "
        "PROCESS | status NAME | logs NAME "
        "[PROCESS] | restart NAME PROCESS | wait NAME PROCESS STATE; inspecting: topics NAME | "
        "hz NAME TOPIC | echo NAME TOPIC | plot NAME TOPIC FIELD | params NAME NODE "
        "--dump/--load FILE | log-level NAME NODE LEVEL (tuilaunch COMMAND -h); in a web "
        "browser: serve [NAME | FILE]. On another machine: ls HOST, and HOST:NAME for NAME "
        "(over ssh). Tab completion: eval \"$(tuilaunch completion bash)\" (or zsh).")
    return parser


SESSIONS = "[HOST:]NAME"
"""A session word's metavar; argparse adds the `...` of several itself."""
SESSIONS_HELP = ("sessions: NAME (here), HOST:NAME, or HOST: for every session there "
                 "(local: is this computer); default: the only one here")


def commands_parser() -> argparse.ArgumentParser:
    """The session commands; each sub-parser's positionals are named `name` (the session),
    `process`, `node`, `topic`, `state`, `level`: completion.py completes them by name."""
    parser = argparse.ArgumentParser(
        prog="tuilaunch", description="Control launches running as sessions.")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    ls = commands.add_parser("ls", help="running sessions")
    ls.add_argument("host", nargs="*", metavar="HOST",
                    help="the sessions on these machines (as ssh names them; local: this "
                    "one), asked in parallel, in one table with a HOST column")
    ls.add_argument("--json", action="store_true", help="one JSON list")
    attach = commands.add_parser("attach", help="the TUI on a running session")
    attach.add_argument("name", nargs="*", metavar=SESSIONS,
                        help=SESSIONS_HELP + "; several: one TUI over all of them")
    attach.add_argument("--scrollback", type=int, default=5000, metavar="LINES")
    attach.add_argument("--tab", choices=TABS, default="nodes",
                        help="the tab shown first (one session)")
    attach.add_argument("--type", metavar="PROCESS", dest="type_into",
                        help="open typing into PROCESS's terminal, as `i` on its row does "
                        "(ctrl+] gives the keys back; one session)")
    attach.add_argument("--read-only", action="store_true",
                        help="a view that changes nothing: stop, start, restart, relaunch, "
                        "typing into a node, parameters, services and log levels are "
                        "refused (q leaves, the launch runs on)")
    # one positional for both forms: `stop A B` is two sessions when every word names
    # one, else a session and its processes (fleet.py's route tells them apart)
    stop = commands.add_parser(
        "stop", help="stop every process of sessions, or some processes of one session",
        usage="tuilaunch stop [-h] [--json] [HOST:]NAME [PROCESS ...]\n"
        "       tuilaunch stop [-h] [--json] [[HOST:]NAME ...]",
        description="Stop sessions (every process, then the session ends), or the "
        "processes named of one session (the others and the session run on). Returns once "
        "they are stopped.")
    stop.add_argument("name", nargs="*", metavar="WORD",
                      help=SESSIONS_HELP + "; or one session, then process ids or node "
                      "names of it")
    stop.add_argument("--json", action="store_true",
                      help="one JSON list: each session or process and its state")
    start = commands.add_parser(
        "start", help="start processes of a session (as t in the TUI)",
        description="Start the processes named (stopped, exited or failed ones; one that "
        "runs is left as it is; one its condition skipped is refused). Returns once they "
        "are started.")
    start.add_argument("name", metavar="[HOST:]NAME", help="the session")
    start.add_argument("process", nargs="+", metavar="PROCESS",
                       help="a process id or node name")
    start.add_argument("--json", action="store_true",
                       help="one JSON list: each process and its state")
    status = commands.add_parser("status", help="each process's state")
    status.add_argument("name", nargs="*", metavar=SESSIONS, help=SESSIONS_HELP)
    status.add_argument("--json", action="store_true", help="one JSON object")
    logs = commands.add_parser("logs", help="the output of a session's processes",
                               usage="tuilaunch logs [-h] [-f] [-n N] [--since T] "
                               "[--level L] [[HOST:]NAME ...] [PROCESS]")
    # the last word is the PROCESS unless it names a session (HOST:NAME, HOST:, or a
    # session here): `logs far talker`, `logs nuc:base arm:base -f`
    logs.add_argument("name", nargs="*", metavar="WORD",
                      help=SESSIONS_HELP + "; then a process id or node name (default: all)")
    logs.add_argument("-f", "--follow", action="store_true", help="keep printing new lines")
    logs.add_argument("-n", "--lines", type=int, metavar="N",
                      help="only the last N lines (as tail -n); with -f, the last N and then "
                      "the new ones")
    logs.add_argument("--since", metavar="T",
                      help="only lines from T on: 30s, 5m, 2h ago, a unix time, or an ISO "
                      "time (2026-11-22T08:30:00, or 08:30 today)")
    logs.add_argument("--level", metavar="L", type=str.upper, choices=LEVELS,
                      help=f"only lines at this ROS level or above ({', '.join(LEVELS)})")
    restart = commands.add_parser("restart", help="restart one process")
    restart.add_argument("name", metavar="[HOST:]NAME")
    restart.add_argument("process")
    restart.add_argument("--prefix", metavar="CMD",
                         help="run it under a tool until a restart without one, e.g. "
                         "'gdb -q -ex run --args' (type into it in the TUI with i)")
    restart.add_argument("--terminal", action="store_true",
                         help="give it a terminal until a restart without --terminal, to "
                         "type into it in the TUI with i (as emulate_tty=True; processes "
                         "get pipes by default, as in ros2 launch)")
    restart.add_argument("--log-level", metavar="LEVEL",
                         help="append --ros-args --log-level LEVEL (debug, info, warn, error, "
                         "fatal; kept across respawns until a restart gives another; '' "
                         "drops it)")
    wait = commands.add_parser(
        "wait", help="wait until a process is in a state (exit status 0) or time runs out (1)")
    wait.add_argument("name", metavar="[HOST:]NAME")
    wait.add_argument("process")
    wait.add_argument("state", help=f"{', '.join(PROCESS_STATES)}, or a lifecycle state: "
                      f"{', '.join(LIFECYCLE_STATES)}")
    wait.add_argument("--timeout", type=float, default=None, metavar="S",
                      help="give up after S seconds (exit status 1)")
    subs = [ls, attach, stop, start, status, logs, restart, wait]
    subs += _inspector_commands(commands)
    completion = commands.add_parser(
        "completion", help="the shell code of Tab completion: "
        "eval \"$(tuilaunch completion bash)\" in ~/.bashrc (or zsh in ~/.zshrc)")
    completion.add_argument("shell", choices=SHELLS)
    subs.append(completion)
    subs.append(_serve_command(commands))
    subs.append(_record_command(commands))
    for sub in subs:
        sub.add_argument("--debug", action="store_true", help=argparse.SUPPRESS)
    return parser


SERVE_PORT = 8000
BLACK_BOX_SIZE = 256
"""`--black-box-size`'s default, in MB."""


def _record_command(commands: argparse._SubParsersAction[argparse.ArgumentParser])\
        -> argparse.ArgumentParser:
    """`record` (record.py runs it)."""
    record = commands.add_parser(
        "record", help="record topics and the output into an MCAP file on this computer, "
        "until Ctrl+C; or write the black box now")
    record.add_argument("name", metavar="[HOST:]NAME", help="the session")
    record.add_argument("topic", nargs="*", metavar="TOPIC",
                        help="the topics (default: every topic the launch's nodes publish)")
    record.add_argument("-o", "--output", metavar="FILE.mcap",
                        help="the file (default NAME-DATE-TIME.mcap here; never overwritten)")
    record.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    record.add_argument("--black-box", action="store_true",
                        help="write the session's black box now, in its log folder")
    record.add_argument("--black-box-on", type=float, metavar="SECONDS",
                        help="switch the session's black box on (0: off) and exit")
    record.add_argument("--black-box-size", type=float, default=BLACK_BOX_SIZE, metavar="MB",
                        help=f"with --black-box-on: its bound in memory (default "
                        f"{BLACK_BOX_SIZE} MB)")
    return record


def _serve_command(commands: argparse._SubParsersAction[argparse.ArgumentParser])\
        -> argparse.ArgumentParser:
    """`serve` (serve.py runs it)."""
    serve = commands.add_parser(
        "serve", help="the TUI in a web browser: a session's, a launch file's (started as a "
        "detached session), or a page listing the sessions",
        description="Serve the TUI at a URL (printed first): each browser tab is a client "
        "of the session, as attach is; closing it or stopping serve stops nothing.")
    serve.add_argument("items", nargs="*", metavar="[HOST:]NAME | FILE [name:=value ...]",
                       help="a session; or a launch file (or PACKAGE FILE) and its "
                       "arguments, started as a detached session first; none: a page of "
                       "the sessions here")
    serve.add_argument("--host", default="127.0.0.1",
                       help="the address to listen on (default 127.0.0.1: this machine "
                       "only; any other needs the token printed in the URL)")
    serve.add_argument("--port", type=int, default=SERVE_PORT,
                       help=f"the port (default {SERVE_PORT})")
    serve.add_argument("--public-url", metavar="URL",
                       help="the URL the browser uses, behind a reverse proxy "
                       "(https://robot.example/tuilaunch)")
    serve.add_argument("--token-file", metavar="FILE",
                       help="the token to ask for, read from FILE (default: a random one, "
                       "made at start, when --host is not loopback)")
    serve.add_argument("--read-only", action="store_true",
                       help="a view that changes nothing (a screen on the wall): every "
                       "key that would stop, start, set or type is refused")
    serve.add_argument("--name", metavar="NAME",
                       help="with FILE: the new session's name")
    return serve


def _inspector_commands(commands: argparse._SubParsersAction[argparse.ArgumentParser])\
        -> list[argparse.ArgumentParser]:
    """topics, hz, echo, params, log-level (inspector.py runs them)."""
    topics = commands.add_parser("topics", help="topics, their types, publishers and "
                                 "subscribers (with their processes) and QoS problems")
    topics.add_argument("name", metavar="[HOST:]NAME", help="the session")
    topics.add_argument("--node", metavar="NODE",
                        help="only this node's topics (full name or process id)")
    topics.add_argument("-v", "--verbose", action="store_true",
                        help="each publisher and subscriber with its node, process and QoS "
                        "(as ros2 topic info -v)")
    topics.add_argument("--json", action="store_true", help="one JSON object")
    hz = commands.add_parser("hz", help="a topic's rate and bandwidth, a block every second "
                             "until Ctrl+C (as ros2 topic hz and bw)")
    hz.add_argument("name", metavar="[HOST:]NAME")
    hz.add_argument("topic")
    hz.add_argument("-w", "--window", type=int, default=HZ_WINDOW, metavar="N",
                    help=f"the rate over the last N messages (default {HZ_WINDOW}, as ros2 "
                    "topic hz)")
    hz.add_argument("--duration", type=float, metavar="S",
                    help="measure for S seconds, print the figures once and exit")
    hz.add_argument("--json", action="store_true",
                    help="one JSON object after --duration (default 5 s)")
    echo = commands.add_parser("echo", help="a topic's messages as YAML, until Ctrl+C")
    echo.add_argument("name", metavar="[HOST:]NAME")
    echo.add_argument("topic")
    echo.add_argument("--count", type=int, metavar="N", help="stop after N messages")
    echo.add_argument("--once", action="store_true", help="stop after one message")
    echo.add_argument("--timeout", type=float, metavar="S",
                      help="stop after S seconds, the wait for a publisher included (exit "
                      "status 1 when fewer than --count, or no message, came)")
    plot = commands.add_parser("plot", help="a live plot of a topic's numeric fields, or "
                               "--csv: one line per message")
    plot.add_argument("name", metavar="[HOST:]NAME")
    plot.add_argument("topic")
    plot.add_argument("fields", nargs="+", metavar="FIELD",
                      help="a numeric field by dotted path: data, pose.pose.position.x, "
                      "ranges[0]; a word starting with / starts another topic, a "
                      "HOST:NAME another session: FIELD... [[HOST:]NAME] [TOPIC FIELD...]")
    plot.add_argument("--csv", action="store_true",
                      help="print time,FIELD,... then one line per message (time in seconds "
                      "since the first, as received) instead of plotting")
    plot.add_argument("--duration", type=float, metavar="S", help="stop after S seconds")
    plot.add_argument("--stamp", action="store_true", help="the time of each message is its "
                      "header.stamp (epoch seconds in the CSV), not when it was received")
    params = commands.add_parser("params", help="a node's live parameters as a params file, "
                                 "or such a file loaded into it")
    params.add_argument("name", metavar="[HOST:]NAME")
    params.add_argument("node", help="full node name or process id")
    what = params.add_mutually_exclusive_group(required=True)
    what.add_argument("--dump", action="store_true",
                      help="print the parameters as YAML a launch file loads")
    what.add_argument("--load", metavar="FILE", help="set the parameters a params file gives")
    level = commands.add_parser("log-level", help="set a node's logger level")
    level.add_argument("name", metavar="[HOST:]NAME")
    level.add_argument("node", help="full node name or process id")
    level.add_argument("level", help=", ".join(NODE_LEVELS))
    return [topics, hz, echo, plot, params, level]
