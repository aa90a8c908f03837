"""`tuilaunch FILE [name:=value ...]`, `tuilaunch PACKAGE FILE [...]`, and the session
commands (`ls`, `attach`, `stop`, ...: see commands.py)."""

from __future__ import annotations

import argparse
import contextlib
import os
import subprocess
import sys
import traceback
from pathlib import Path
from typing import TYPE_CHECKING

from ..engine.describe.python.loader import LoadedFile, load_file, set_command_line
from ..engine.errors import LaunchError, PackageError
from ..engine.packages import ensure_environment, find_launch_file_in_share
from ..engine.plan.command.prefix import prefix_arguments
from ..engine.plan.resolve import declared_arguments, resolve
from ..engine.run.lean_asyncio import asyncio_without_tls

if TYPE_CHECKING:
    from ..engine.plan.machines import Placement


def split_items(items: list[str]) -> tuple[list[str], dict[str, str]]:
    positional: list[str] = []
    arguments: dict[str, str] = {}
    for item in items:
        if ":=" in item:
            name, value = item.split(":=", 1)
            if not name:
                raise LaunchError(f"launch argument {item!r} has no name",
                                  hint="write name:=value")
            arguments[name] = value
        else:
            positional.append(item)
    return positional, arguments


def find_launch_file(positional: list[str]) -> str:
    if len(positional) == 1:
        path = positional[0]
        if os.path.isdir(path):
            raise PackageError(f"{path} is a directory, not a launch file",
                               hint="give the launch file inside it, or PACKAGE FILE")
        if not os.path.isfile(path):
            from .suggest import missing_file

            raise missing_file(path)
        return path
    if len(positional) == 2:
        from .suggest import missing_in_package, missing_package

        package, name = positional
        unknown = missing_package(package)
        if unknown is not None:
            raise unknown
        try:
            return str(find_launch_file_in_share(package, name))
        except PackageError as exc:
            raise missing_in_package(package, name, exc) from None
    raise LaunchError(f"expected FILE or PACKAGE FILE, got {' '.join(positional)!r}",
                      hint="launch arguments are written name:=value")


def _placement(options: argparse.Namespace) -> Placement | None:
    """`--machines FILE` (or, on another machine's share, the text the launching side
    sent, and `--share MACHINE`)."""
    if options.machines is None and options.machines_text is None:
        if options.share is not None:
            raise LaunchError("--share needs --machines")
        return None  # a launch on this machine alone does not load the machines' code
    from ..engine.plan.machines import load_placement, placement_from_text

    if options.machines_text is not None:
        return placement_from_text(options.machines_text, options.machines or
                                   "the launching side's machines file", options.share)
    return load_placement(options.machines, options.share)


def _show_arguments(loaded: LoadedFile, arguments: dict[str, str]) -> int:
    """`--show-args`: listed without values for the required ones, as ros2 launch lists them;
    what could not be followed (an include that needs a value) is a warning."""
    from .printing import format_arguments

    found, stopped = declared_arguments(loaded, arguments)
    print(format_arguments(found, loaded.path), end="")
    if stopped is not None:
        print(f"tuilaunch: warning: some arguments may be missing: {stopped}",
              file=sys.stderr)
    return 0


def is_command(argv: list[str]) -> bool:
    """A session command, unless the word names an existing file (launched, as it always
    was); `tuilaunch -- WORD ...` forces the launch form, e.g. for a package named `status`."""
    from .parsers import COMMANDS

    return bool(argv) and argv[0] in COMMANDS and not os.path.exists(argv[0])


def _reopen_closed_std_streams() -> None:
    """`tuilaunch ... >&-` (or `<&-`, `2>&-`): a closed 0, 1 or 2 would be handed to the next
    file opened, so a log file or a node's pipe would receive what is meant for the
    terminal. Each one closed becomes /dev/null, and a closed stdout is said once."""
    closed = []
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            closed.append(fd)
            null = os.open(os.devnull, os.O_RDWR)
            if null != fd:  # the lowest free number: it is fd itself unless a lower one was
                os.dup2(null, fd)
                os.close(null)
    for fd, name in ((0, "stdin"), (1, "stdout"), (2, "stderr")):
        if fd in closed or getattr(sys, name) is None:
            setattr(sys, name, open(fd, "r" if fd == 0 else "w", closefd=False,
                                    errors="backslashreplace"))
    if 1 in closed:
        print("tuilaunch: stdout is closed: nothing is printed; every node's output is in "
              "its log file", file=sys.stderr)


def main(argv: list[str] | None = None) -> int:
    asyncio_without_tls()  # a launch, the TUI and the session commands: 4 MB less each
    _reopen_closed_std_streams()
    try:
        return _main(argv)
    except BrokenPipeError:
        # `tuilaunch ... | head -1`: the reader is gone, which is no error of ours; point
        # stdout at /dev/null so the interpreter's final flush stays quiet too
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return 0
    except KeyboardInterrupt:
        # Ctrl+C before anything runs (a slow file or xacro loading, `logs -f`, `wait`):
        # nothing was started, so there is nothing to stop and no traceback to show
        print("tuilaunch: interrupted", file=sys.stderr)
        return 130


def _main(argv: list[str] | None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] in (["__proxy"], ["__ls"]):
        # hidden: the far end of an ssh link (`ssh HOST tuilaunch __proxy NAME`), not for
        # people, so not in --help
        from ..engine.run.machines import proxy

        return proxy.main(argv)
    if is_command(argv) and argv[0] == "record":  # one session at a time: record.py
        from .commands import main as session_command
        from .record import cmd_record

        ensure_environment()
        return session_command(argv, cmd_record)
    if is_command(argv):
        from .fleet import main as command_main

        ensure_environment()
        return command_main(argv)
    if argv[:1] == ["--"]:
        argv = argv[1:]
    from .parsers import launch_parser

    options = launch_parser().parse_intermixed_args(argv)
    ensure_environment()
    if options.on:  # the file is HOST's, read and run there (client/session_start.py)
        from .start_on import start_on

        return start_on(options)
    # a launch file's own print() must not corrupt the JSON a tool reads on stdout
    file_output = contextlib.redirect_stdout(sys.stderr) if options.print_plan and \
        options.json else contextlib.nullcontext()
    try:
        positional, arguments = split_items(options.items)
        placement = _placement(options)
        options.placement = placement
        if options.black_box is not None:  # the server started below reads it (record/)
            from .record import black_box_option

            black_box_option(options.black_box, options.black_box_size)
        if options.show_all_subprocesses_output:  # ros2launch's way: its children see it
            os.environ["OVERRIDE_LAUNCH_PROCESS_OUTPUT"] = "both"
        # after the user's own name:=value, so these win, as in ros2 launch
        for item in prefix_arguments(options.launch_prefix, options.launch_prefix_filter):
            key, value = item.split(":=", 1)
            arguments[key] = value
        from .suggest import check_assignments, not_a_launch_file

        check_assignments(positional)
        path = find_launch_file(positional)
        # `ros2 launch FILE --show-args` shows the flag to the file (simple_launch reads it)
        set_command_line(positional + (["--show-args"] if options.show_args else []),
                         arguments)
        if _in_tui(options):
            # the server loads the file, once, as ros2 launch does; the TUI draws its plan
            return _run_tui(path, arguments, options, positional)
        with file_output:
            try:
                loaded = load_file(path)
            except LaunchError as exc:
                raise not_a_launch_file(path, exc) from None
            if options.show_args:
                return _show_arguments(loaded, arguments)
            # any value is taken, as ros2 launch takes it (launch arguments are strings;
            # simple_launch's examples pass x:=3.5 for a default of 1); choices refuse there
            plan = resolve(loaded, arguments)
            if placement is not None:
                placement.apply(plan)
    except LaunchError as exc:
        if options.debug:
            traceback.print_exc()
        print(f"tuilaunch: error: {exc}", file=sys.stderr)
        return 2
    if options.print_plan:
        if options.json:
            import json

            print(json.dumps(plan.to_json(), indent=2))
        else:
            from .printing import format_placement, format_tree

            print(format_tree(plan), end="")
            if placement is not None:
                print(format_placement(plan, placement), end="")
        problems = plan.problems()
        for problem in problems:
            print(f"tuilaunch: error: {problem}", file=sys.stderr)
        if problems:
            print("tuilaunch: the processes above cannot start: install or source what they "
                  "need, or turn off the arguments that enable them", file=sys.stderr)
        return 3 if problems else 0
    for warning in plan.warnings:
        print(f"tuilaunch: warning: {warning}", file=sys.stderr)
    log_dir = _log_dir()
    if log_dir is None:
        return 2
    if options.detach:
        return _start_detached(path, arguments, options, log_dir, positional)
    from .headless import run_headless

    return run_headless(plan, log_dir, placement=placement, command=positional,
                        arguments=arguments)


def _in_tui(options: argparse.Namespace) -> bool:
    """The launch is followed in a TUI: not printed, detached nor headless, on a terminal."""
    return not (options.print_plan or options.show_args or options.detach or
                options.headless) and sys.stdout.isatty() and sys.stdin.isatty()


def _log_dir() -> Path | None:
    """This launch's log folder, made; None once why not is said."""
    from .headless import run_log_dir

    log_dir = run_log_dir()
    try:
        log_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        print(f"tuilaunch: error: cannot create the log folder {log_dir} (set by ROS_LOG_DIR, "
              f"ROS_HOME or ~/.ros): {exc.strerror or exc}", file=sys.stderr)
        return None
    return log_dir


def _start_server(path: str, arguments: dict[str, str], options: argparse.Namespace,
                  log_dir: Path, positional: list[str])\
        -> tuple[str, subprocess.Popen[bytes]] | None:
    """The launch's session server, started; None once its error is said."""
    from .commands import start_session

    placement: Placement | None = options.placement
    placed = None if placement is None else {
        "text": placement.text, "path": placement.machines.path, "share": placement.share}
    try:
        return start_session(path, arguments, options.name, log_dir, positional,
                             placement=placed)
    except LaunchError as exc:
        print(f"tuilaunch: error: {exc}", file=sys.stderr)
        return None


def _start_detached(path: str, arguments: dict[str, str], options: argparse.Namespace,
                    log_dir: Path, positional: list[str]) -> int:
    started = _start_server(path, arguments, options, log_dir, positional)
    if started is None:
        return 2
    print(started[0])
    return 0


def _run_tui(path: str, arguments: dict[str, str], options: argparse.Namespace,
             positional: list[str]) -> int:
    """The launch runs in a session server, started first: it loads the file while the TUI
    imports (the TUI never loads it); this TUI is its first client and draws the plan the
    server resolved, and the server's first process starts once the tree is on screen."""
    from ..client.session_start import spawn_session
    from .commands import report_end

    log_dir = _log_dir()
    if log_dir is None:
        return 2
    placement: Placement | None = options.placement
    placed = None if placement is None else {
        "text": placement.text, "path": placement.machines.path, "share": placement.share}
    try:
        starting = spawn_session(path, arguments, options.name, log_dir, positional,
                                 placement=placed, owner=True)
    except LaunchError as exc:  # the name is taken
        print(f"tuilaunch: error: {exc}", file=sys.stderr)
        return 2
    try:
        from ..tui.app import launch_app  # imported while the server loads the file

        app = launch_app(path, arguments, log_dir, starting.name, positional, placement,
                         starting=starting, scrollback=options.scrollback,
                         keep_on_hangup=options.keep_on_hangup)
        status = app.run()
    except BaseException:  # Ctrl+C while importing: the server goes too, nothing started
        starting.process.terminate()
        raise
    if app.start_error is not None:
        error = LaunchError(app.start_error)
        if starting.own_error is not None:  # the file's own error, as a local load says it
            from .suggest import not_a_launch_file

            error = not_a_launch_file(path, error)
        print(f"tuilaunch: error: {error}", file=sys.stderr)
        return 2
    if app.quit_before_start:
        return status or 0  # its server, if it came up, stops every process it started
    report_end(app, starting.name)
    server = app.server_process
    if not app.detached and server is not None:
        try:
            server.wait(timeout=15)
        except subprocess.TimeoutExpired:
            pass  # still stopping its processes on its own; nothing is left half-done
    return status or 0


if __name__ == "__main__":
    sys.exit(main())
