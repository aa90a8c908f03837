"""Headless pilot tests of every panel against real nodes started from examples/."""

from __future__ import annotations

import os
import pty
import select
import signal
import subprocess
import sys
import time
from collections.abc import AsyncIterator, Callable, Iterator
from contextlib import asynccontextmanager, contextmanager
from pathlib import Path
from typing import Any, TypeVar, cast

import pytest
from textual.css.query import NoMatches
from textual.pilot import Pilot
from textual.widget import Widget
from textual.widgets import Checkbox, DataTable, Input

from tuilaunch.client.link import send_once
from tuilaunch.client.session_start import start_session
from tuilaunch.engine.errors import LaunchError
from tuilaunch.engine.run.events import LifecycleChanged
from tuilaunch.engine.run.vocabulary.requests import ShutdownLaunch
from tuilaunch.tui.app import TuiLaunchApp, launch_app, make_app
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.args_panel import ArgsPanel
from tuilaunch.tui.screens.dialogs import QuitScreen
from tuilaunch.tui.screens.output_panel import OutputPanel
from tuilaunch.tui.screens.params_panel import ParamsPanel
from tuilaunch.tui.screens.services_panel import ServicesPanel
from tuilaunch.tui.screens.tree_panel import LaunchTree

from ..conftest import EXAMPLES, session_folders
from .proc_tree import end, servers_of

BRINGUP = str(EXAMPLES / "bringup.py")
W = TypeVar("W", bound=Widget)


async def until(pilot: Pilot, check: Callable[[], object], limit: float = 60.0,
                every: Callable[[], object] | None = None,
                explain: Callable[[], object] | None = None) -> None:
    """Lets the app run until `check` holds, calling `every` once a second (a refresh);
    the limit only guards against a hang, and `explain` says what was seen instead."""
    waited = 0.0
    while not holds(check):
        assert waited < limit, f"condition never held: {check}" + (
            f"; {explain()}" if explain is not None else "")
        if every is not None and int(waited * 20) % 20 == 0:
            every()
        await pilot.pause(0.05)
        waited += 0.05


async def tab_panel(pilot: Pilot, app: TuiLaunchApp, key: str, kind: type[W]) -> W:
    """Tab `key` (3, 4, 5) opened as a user opens it, and its panel, made the first time the
    tab shows (tui/tab_panels.py): the tab switches once it is there."""
    await pilot.press(key)
    tab = {"3": "services", "4": "params", "5": "topics"}[key]
    await until(pilot, lambda: app.tabs.active == tab)
    return app.tabs.query_one(kind)


def holds(check: Callable[[], object]) -> bool:
    """Whether `check` holds; not yet while a widget it reads is not mounted (a screen
    pushed and not yet composed, on a loaded machine), nor while a row it reads is not drawn
    (the tree is the plan the session's server sends, once it has loaded the file)."""
    try:
        return bool(check())
    except (NoMatches, KeyError):
        return False


@asynccontextmanager
async def launched(path: str, arguments: dict[str, str], tmp_path: Path,
                   size: tuple[int, int] = (100, 32),
                   prepare: Callable[[TuiLaunchApp], None] | None = None, **options: Any)\
        -> AsyncIterator[tuple[TuiLaunchApp, Pilot]]:
    """The TUI as `tuilaunch FILE` runs it (launch_app): the launch's session server starts
    at once and loads the file, its processes start once the tree shows, and this TUI is its
    owning client; in a private session folder.
    When the test is over the session is stopped, and nothing it started is left.
    `prepare(app)`: before it runs."""
    with session_folders(tmp_path / "log"):
        app = launch_app(path, arguments, tmp_path / "log", **options)
        if prepare is not None:
            prepare(app)
        try:
            async with app.run_test(size=size) as pilot:
                try:
                    yield app, pilot
                finally:
                    if app.supervisor is not None and app.is_running and not app.quitting:
                        try:
                            await app.engine.run(app.supervisor.shutdown("test over"))
                        except (LaunchError, ConnectionError):
                            pass  # it ended meanwhile (the test stopped it)
        finally:
            reap(app.server_process, tmp_path)


def reap(server: subprocess.Popen[bytes] | None, tmp_path: Path) -> None:
    """A session server asked to stop, waited for (it stops every process it started
    first), then whatever of the test's servers is left ended."""
    if server is not None:
        try:
            server.wait(timeout=60)
        except subprocess.TimeoutExpired:
            end([server.pid])
    end(servers_of(tmp_path))


@contextmanager
def attached(path: str, arguments: dict[str, str], tmp_path: Path) -> Iterator[str]:
    """A session of `path` started as `tuilaunch PATH --detach` does, in a private session
    folder, for a TUI made with make_app(..., session_name=NAME) to attach to; stopped, and
    nothing it started left, at the end. Yields its name."""
    with session_folders(tmp_path / "log"):
        name, server = start_session(path, arguments, None, tmp_path / "log")
        try:
            yield name
        finally:
            send_once(name, ShutdownLaunch("test over"))
            reap(server, tmp_path)


@asynccontextmanager
async def tui(tmp_path: Path, *args: str, path: str = BRINGUP, size: tuple[int, int] = (100, 32),
              **options: Any) -> AsyncIterator[tuple[TuiLaunchApp, Pilot]]:
    """`tuilaunch PATH name:=value ...` in a terminal of `size`."""
    arguments = dict(a.split(":=", 1) for a in args)
    async with launched(path, arguments, tmp_path, size, **options) as opened:
        yield opened


def states(app: TuiLaunchApp) -> dict[str, str]:
    """The processes' states as the session reports them ({} until the TUI follows it)."""
    return {} if app.supervisor is None else app.supervisor.states


def row_text(app: TuiLaunchApp, ref: str) -> str:
    return str(app.query_one(LaunchTree).rows[ref].label)


def pids(app: TuiLaunchApp) -> dict[str, int]:
    return {} if app.supervisor is None else app.supervisor.pids


async def test_select_a_node_see_its_output_stop_restart_and_search(tmp_path):
    async with tui(tmp_path, "robot:=tui1", "rate:=20", "services:=false") as (app, pilot):
        await until(pilot, lambda: "running" in row_text(app, "talker-1"))
        panel = app.query_one(OutputPanel)
        # keyboard only: root, "all nodes", "ns /tui1", then the talker
        await pilot.press("down", "down", "down")
        assert panel.view.process == "talker-1"
        await until(pilot, lambda: any("Publishing" in line for line in panel.pane_lines()))
        assert not any("[listener-2]" in line or "I heard" in line
                       for line in panel.pane_lines())

        first_pid = pids(app)["talker-1"]
        await pilot.press("s")
        await until(pilot, lambda: "exited" in row_text(app, "talker-1"))
        assert states(app)["listener-2"] == "running"  # the others keep running
        await pilot.press("r")
        await until(pilot, lambda: states(app)["talker-1"] == "running")
        assert pids(app)["talker-1"] != first_pid

        await pilot.press("slash")
        await pilot.press(*"says hi")
        await pilot.press("enter")
        status = str(app.query_one("#output-status").render())
        assert panel.search == "says hi" and "/says hi 1/" in status
        await pilot.press("n")
        assert panel.match_index == 1

        await pilot.press("a")
        assert panel.view.process is None
        await until(pilot, lambda: any(line.startswith("[listener-2]")
                                       for line in panel.pane_lines()))
        await pilot.press("l", "l", "l")  # ERROR and above: the INFO chatter is gone
        assert not any("Publishing" in line for line in panel.pane_lines())


async def test_editing_an_argument_previews_then_relaunches_only_what_changes(tmp_path):
    async with tui(tmp_path, "robot:=tui2", "services:=false") as (app, pilot):
        await until(pilot, lambda: states(app).get("listener-2") == "running"
                    and states(app).get("talker-1") == "running")
        talker_pid = pids(app)["talker-1"]
        await pilot.press("2")
        app.query_one("#arg-listener", Checkbox).value = False
        await pilot.pause()
        preview = str(app.query_one("#args-preview").render())
        assert "would stop: listener-2" in preview
        assert row_text(app, "listener-2").startswith("-")
        assert states(app)["listener-2"] == "running"  # nothing changes before applying
        assert app.query_one("#row-listener").has_class("changed")

        await pilot.press("f5")
        await until(pilot, lambda: states(app)["listener-2"] == "skipped")
        assert app.session.arguments["listener"] == "false"
        assert pids(app)["talker-1"] == talker_pid  # unaffected nodes keep running
        # the answer to the apply may come after the events that stopped it
        await until(pilot, lambda: "Applied. Stopped: listener-2" in str(
            app.query_one("#args-preview").render()))


async def test_a_checked_box_keeps_the_spelling_the_command_line_used(tmp_path):
    """bringup.py's default is simple_launch's True ("True"); started with listener:=false,
    checking the box applied listener:=True: a value written two ways at once."""
    async with tui(tmp_path, "robot:=tui8", "services:=false", "listener:=false") as (
            app, pilot):
        await until(pilot, lambda: states(app).get("talker-1") == "running")
        await pilot.press("2")
        box = app.query_one("#arg-listener", Checkbox)
        assert str(box.label) == "false"
        box.value = True
        await pilot.pause()
        assert str(box.label) == "true"
        await pilot.press("f5")
        await until(pilot, lambda: app.session.arguments.get("listener") == "true")
        await until(pilot, lambda: states(app).get("listener-2") == "running")


ERRORING = """
from simple_launch import SimpleLauncher
sl = SimpleLauncher()
sl.declare_arg('copies', 1, description='how many talkers (at most 3)')
def setup():
    if sl.arg('copies') > 3:
        raise ValueError('at most 3 copies')
    for i in range(sl.arg('copies')):
        sl.node('tuilaunch_demos', 'talker', name=f'copy{i}')
    return sl.launch_description()
generate_launch_description = sl.launch_description(opaque_function=setup)
"""


async def test_a_bad_argument_value_shows_its_error_and_applies_nothing(tmp_path, write):
    path = write(ERRORING)
    async with tui(tmp_path, path=str(path)) as (app, pilot):
        await until(pilot, lambda: states(app).get("copy0-1") == "running")
        await pilot.press("2")
        field = app.query_one("#arg-copies", Input)
        field.value = "5"
        preview = app.query_one("#args-preview")
        # the preview loads the file off the UI's thread: on a busy machine it takes a while
        await until(pilot, lambda: preview.has_class("error"))
        assert "raised ValueError: at most 3 copies" in str(preview.render())
        await pilot.press("f5")
        await pilot.pause()
        assert app.session.arguments == {} and list(pids(app)) == ["copy0-1"]
        field.value = "2"
        await until(pilot, lambda: "would start: copy1-2" in str(preview.render()))


async def test_service_panel_calls_a_real_service_and_shows_errors(tmp_path):
    async with tui(tmp_path, "robot:=tui3", "listener:=false") as (app, pilot):
        await until(pilot, lambda: states(app).get("service_server-4") == "running")
        panel = await tab_panel(pilot, app, "3", ServicesPanel)
        await until(pilot, lambda: "/tui3/enable" in dict(panel.services),
                    every=panel.refresh_listing)
        await pilot.press("slash", *"tui3/enable")  # the tab shows the list; / filters it
        await pilot.press("enter")  # picks the first match and moves to the form
        assert panel.selected == ("/tui3/enable", "std_srvs/srv/SetBool")
        # the form comes once its fields are known (a session is asked for them)
        await until(pilot, lambda: app.focused is not None and app.focused.id == "field-data")
        field = app.query_one("#field-data", Input)
        assert app.focused is field  # straight into the form
        assert field.value == "false"  # pre-filled with the type's default
        field.value = "true"
        await pilot.press("enter")
        response = app.query_one("#svc-response")
        await until(pilot, lambda: "message: enabled" in str(response.render()))
        assert "success: true" in str(response.render())

        field.value = "yes"
        field.focus()
        await pilot.press("enter")
        await until(pilot, lambda: "needs a boolean" in str(response.render()))
        assert response.has_class("error")

        assert app.supervisor is not None
        await app.engine.run(app.supervisor.command("stop", "service_server-4"))
        field.value = "true"
        field.focus()
        await pilot.press("enter")
        await until(pilot, lambda: "not available" in str(response.render()), limit=60)
        assert [r.ok for r in panel.history] == [True, False, False]

        # Enter on a row of the list picks the service and moves on to its request
        listing = app.query_one("#svc-list")
        listing.focus()
        await pilot.pause()
        await pilot.press("enter")
        await until(pilot, lambda: isinstance(app.focused, Input)
                    and app.focused.id == "field-data")


async def test_parameter_panel_sets_and_reads_back_a_real_parameter(tmp_path):
    async with tui(tmp_path, "robot:=tui4", "listener:=false", "services:=false") as (app, pilot):
        await until(pilot, lambda: states(app).get("set_parameters-1") == "done")
        panel = await tab_panel(pilot, app, "4", ParamsPanel)
        await until(pilot, lambda: "/tui4/control/configurable" in panel.nodes,
                    every=panel.refresh_listing)
        await pilot.press("slash", *"tui4/control")  # the tab shows the list; / filters it
        await pilot.press("enter")
        table = app.query_one("#prm-table", DataTable)
        await until(pilot, lambda: table.row_count > 0 and "mode" in panel.params)
        assert panel.params["mode"].value == "patrol"  # set by the launch file's action
        table.move_cursor(row=list(panel.params).index("mode"))
        table.focus()
        await pilot.pause()
        assert panel.current == "mode"
        edit = app.query_one("#prm-edit", Input)
        result = app.query_one("#prm-result")
        await pilot.press("enter")  # Enter on the row: into its value's field
        assert app.focused is edit

        edit.value = "dock"
        await pilot.press("enter")
        await until(pilot, lambda: "now reports dock" in str(result.render()))
        # the node itself logs the change it accepted
        await until(pilot, lambda: any("parameter mode set to 'dock'" in line
                                       for line in app.store.text(View("configurable-3"))))

        edit.value = "fly"
        await pilot.press("enter")
        await until(pilot, lambda: "refused mode = fly" in str(result.render()))
        assert "mode must be idle, patrol or dock" in str(result.render())

        table.move_cursor(row=list(panel.params).index("speed"))
        await pilot.pause()
        edit.value = "fast"
        await pilot.press("enter")
        await until(pilot, lambda: "speed (float)" in str(result.render()))
        assert result.has_class("error")


@pytest.mark.parametrize("tab", ["4", "3"])
async def test_the_first_look_at_params_or_services_lists_the_running_nodes(tmp_path, tab):
    """That first look starts the UI's ROS connection: what the tab lists is the graph, not
    the nothing a new participant knows before discovery (the tab listed once, and the
    user had to find the Refresh button), and it keeps up while it shows."""
    async with tui(tmp_path, "robot:=tui7", "listener:=false") as (app, pilot):
        await until(pilot, lambda: any("Publishing" in line
                                       for line in app.store.text(View("talker-1"))))
        await until(pilot, lambda: states(app).get("service_server-4") == "running")
        if tab == "4":
            params = await tab_panel(pilot, app, tab, ParamsPanel)
            await until(pilot, lambda: "/tui7/talker" in params.nodes)
            # and the list keeps up while it shows: the talker stopped leaves it, started
            # again it comes back, no Refresh pressed
            await pilot.press("1")
            app.launch_tree.move_cursor(app.launch_tree.rows["talker-1"])
            await pilot.press("s", "4")
            await until(pilot, lambda: "/tui7/talker" not in params.nodes)
            await pilot.press("1", "t", "4")
            await until(pilot, lambda: "/tui7/talker" in params.nodes)
        else:
            services = await tab_panel(pilot, app, tab, ServicesPanel)
            await until(pilot, lambda: "/tui7/reset" in dict(services.services))
            await pilot.press("slash", *"tui7/reset")
            listing = services.query_one("#svc-list")
            await until(pilot, lambda: listing.border_title == "1 service")


async def test_an_empty_graph_reads_as_still_discovering_not_as_nothing_there(write, tmp_path):
    path = write("""
        from launch import LaunchDescription
        from launch.actions import ExecuteProcess
        def generate_launch_description():
            return LaunchDescription([ExecuteProcess(name='plain', cmd=['sleep', '600'])])
        """)
    async with tui(tmp_path, path=str(path)) as (app, pilot):
        services = await tab_panel(pilot, app, "3", ServicesPanel)
        listing = services.query_one("#svc-list")
        # no node of the launch has a service: the list says discovery goes on
        await until(pilot, lambda: services.answered)
        await until(pilot, lambda: str(listing.border_title).startswith(
            "no service yet, discovering (asked every 2 s)"))
        # a search that finds nothing says so: the count, not discovery
        await pilot.press("slash", *"get_parameters")
        await until(pilot, lambda: listing.border_title == "0 services")


async def test_quit_asks_while_nodes_run_and_leaves_no_process(tmp_path):
    async with tui(tmp_path, "robot:=tui5") as (app, pilot):
        await until(pilot, lambda: len(pids(app)) >= 4)
        running = list(pids(app).values())
        await pilot.press("q")
        assert isinstance(app.screen, QuitScreen)
        await pilot.press("n")
        assert not isinstance(app.screen, QuitScreen) and pids(app)
        await pilot.press("q")
        await pilot.press("y")
        await until(pilot, lambda: not pids(app))
    for pid in running:
        assert not os.path.exists(f"/proc/{pid}") or open(f"/proc/{pid}/stat").read().split()[
            2] == "Z"


WAITING = """
from simple_launch import SimpleLauncher
from simple_launch.events import When
def generate_launch_description():
    sl = SimpleLauncher()
    sl.declare_arg('sim', False, description='run the simulated base')
    sl.declare_arg('robot', 'r1', description='robot name')
    sl.declare_arg('mode', 'idle', choices=['idle', 'patrol'], description='start mode')
    with sl.group(ns=sl.arg('robot'), when=When(delay=600.0)):
        sl.node('tuilaunch_demos', 'talker')
        with sl.group(if_arg='sim'):
            sl.node('tuilaunch_demos', 'listener', name='base')
    return sl.launch_description()
"""


async def followed(pilot: Pilot) -> None:
    """Until the TUI follows its session (the tree drawn with the session's states)."""
    app = cast(TuiLaunchApp, pilot.app)
    await until(pilot, lambda: app.supervisor is not None)
    await pilot.pause()


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_layout_snapshot_nodes_tab(snap_compare, write, tmp_path, size):
    path = str(write(WAITING, "layout.py"))
    with attached(path, {}, tmp_path) as name:
        app = make_app(path, {}, tmp_path / "log", session_name=name)
        assert snap_compare(app, terminal_size=size, run_before=followed)


def test_layout_snapshot_args_tab(snap_compare, write, tmp_path):
    path = str(write(WAITING, "layout.py"))
    with attached(path, {}, tmp_path) as name:
        app = make_app(path, {}, tmp_path / "log", session_name=name)
        assert snap_compare(app, terminal_size=(80, 24), press=["2"], run_before=followed)


def test_args_form_editors_follow_argument_types(write, tmp_path):
    import asyncio

    from textual.widgets import Select

    async def scenario() -> None:
        async with launched(str(write(WAITING, "layout.py")), {"sim": "true"}, tmp_path,
                            (80, 24)) as (app, pilot):
            await followed(pilot)
            form = app.query_one(ArgsPanel)
            assert isinstance(form.query_one("#arg-sim"), Checkbox)
            assert form.query_one("#arg-sim", Checkbox).value is True
            assert isinstance(form.query_one("#arg-mode"), Select)
            assert isinstance(form.query_one("#arg-robot"), Input)
            assert form.query_one("#row-sim").has_class("changed")
            assert not form.query_one("#row-robot").has_class("changed")

    asyncio.run(scenario())


@pytest.mark.parametrize("how", [signal.SIGHUP, signal.SIGTERM])
def test_tui_in_a_terminal_stops_everything_when_the_terminal_hangs_up(tmp_path, how):
    """The ssh session drops (SIGHUP) or systemd stops it (SIGTERM): nothing survives."""
    master, slave = pty.openpty()
    env = {**os.environ, "ROS_LOG_DIR": str(tmp_path), "TERM": "xterm-256color"}
    proc = subprocess.Popen([sys.executable, "-m", "tuilaunch", BRINGUP, "robot:=tui_hup"],
                            stdin=slave, stdout=slave, stderr=slave, env=env,
                            start_new_session=True)
    os.close(slave)
    screen = b""
    try:
        deadline = time.monotonic() + 60
        while b"5 running" not in screen and time.monotonic() < deadline:
            ready, _, _ = select.select([master], [], [], 0.5)
            if ready:
                screen += os.read(master, 65536)  # a terminal that is read, as a real one
        assert b"5 running" in screen
        launch_log = next(tmp_path.glob("*-tuilaunch-*")) / "launch.log"
        children = [int(w[4:]) for line in launch_log.read_text().splitlines()
                    if " started " in line for w in line.split() if w.startswith("pid=")]
        assert len(children) == 5
        os.kill(proc.pid, how)
        after = b""
        end = time.monotonic() + 60
        while time.monotonic() < end:  # to the terminal's end: the shell's last lines too
            if select.select([master], [], [], 0.2)[0]:
                try:
                    data = os.read(master, 65536)
                except OSError:
                    break
                if not data:
                    break
                after += data
            elif proc.poll() is not None:
                break
        status = proc.wait(timeout=30)
        if how == signal.SIGTERM:
            # as ros2 launch: a run stopped by SIGTERM exits 1, and the shell is told why
            assert status == 1
            assert b"tuilaunch: received SIGTERM: every process of session" in after
        else:
            assert status == 0
        gone = time.monotonic() + 30
        while any(os.path.exists(f"/proc/{p}") for p in children) and time.monotonic() < gone:
            time.sleep(0.1)
        assert not [p for p in children if os.path.exists(f"/proc/{p}")]
        said = {signal.SIGHUP: "the terminal hung up (SIGHUP)", signal.SIGTERM: "SIGTERM"}[how]
        assert f"shutdown  reason={said}" in launch_log.read_text()  # why, for later
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        os.close(master)


STUBBORN_TUI = """
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([ExecuteProcess(name='stubborn', cmd=[
        'sh', '-c', 'trap "" INT; echo holding out; sleep 600'])])
"""


async def test_an_engine_event_after_the_screens_closed_is_no_error(write, tmp_path):
    """The engine's events keep coming while the app closes: a lifecycle node's last state
    came after Textual had closed the screens (seen under load) and ended the TUI in a
    traceback. One is delivered there now (Textual's `_close_all`, which the exit awaits)."""
    delivered = []
    async with launched(str(write(STUBBORN_TUI)), {}, tmp_path, (80, 24)) as (app, pilot):
        await followed(pilot)
        close_all = app._close_all

        async def then_an_event() -> None:
            await close_all()
            assert not app.screen_stack
            # as the drain does: the view shows it, the app acts on its news
            last = LifecycleChanged("stubborn-1", reason="finalized")
            app.news_shown(app.view.show_events([last]))
            delivered.append(True)

        app._close_all = then_an_event  # type: ignore[method-assign]
        app.exit()
    assert delivered and app.return_code == 0


async def test_quit_shows_which_processes_are_still_stopping(write, tmp_path):
    # SIGTERM after 4 s, as `sigterm_timeout:=4` on the command line says
    async with launched(str(write(STUBBORN_TUI)), {"sigterm_timeout": "4"}, tmp_path,
                        (80, 24)) as (app, pilot):
        await until(pilot, lambda: any("holding out" in line
                                       for line in app.store.text(View("stubborn-1"))))
        await pilot.press("q", "y")
        status = app.query_one("#status")
        assert "stopping stubborn-1" in str(status.render())
        # the row says so when the session's Stopping event comes (every client's does)
        await until(pilot, lambda: "stopping" in row_text(app, "stubborn-1"))
        # SIGINT is ignored; SIGTERM after the timeout ends it
        await until(pilot, lambda: not pids(app), limit=60)
