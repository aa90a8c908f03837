"""One TUI over two robots (`tuilaunch attach robot1:base robot2:arm`), through real sshd
"machines" on 127.0.0.1, each robot's launch on a ROS domain of its own: a root per
session, keys that act on the selected session alone, and a lost link to one robot that
leaves the other live.
"""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
from pathlib import Path

import pytest
from textual import events
from textual.widgets import Input, Static

from tuilaunch.client import remote_supervisor
from tuilaunch.tui.fleet.app import FleetApp, FleetHelp
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.dialogs import ChoiceScreen, ConfirmScreen
from tuilaunch.tui.screens.interact_dialogs import CommandScreen, PrefixPrompt
from tuilaunch.tui.session_view import SessionView

from ..conftest import run_cli, wait_for
from .sshd import Machines, alive, machines_fixture, proxies_on  # noqa: F401
from .test_fleet_cli import domain, start, start_all, with_gone_host
from .test_lifecycle_tui import LIFECYCLE
from .test_sessions import Terminal, detached_with, run_cli_together, runtime, tl  # noqa: F401
from .test_tui import until


def starts(member: SessionView, process: str) -> int:
    """How many times the member's pane says `process` started."""
    return sum("process started with pid" in line.text
               for line in member.store.lines(View(process)))


def ticks(member: SessionView) -> int:
    return sum(line.text.startswith("tick") for line in member.store.lines(View("ticker-1")))


def notices(app: FleetApp) -> list[str]:
    """What the app says in toasts from here on (each as it is said)."""
    said: list[str] = []
    notify = app.notify
    app.notify = lambda message, **kw: (said.append(str(message)),  # type: ignore
                                        notify(message, **kw))
    return said


async def select(pilot, member: SessionView, process: str) -> None:
    """The row of `process` in the member's tree, selected as the arrows would (again
    until it holds: a tree not laid out yet puts the cursor back on its root)."""
    member.tree.focus()
    row = member.tree.rows[process]

    def there() -> bool:
        if member.tree.cursor_node is not row:
            member.tree.move_cursor(row)
        # and the session selected (its header, its keys): the tree's focus is told
        return member.tree.cursor_node is row and pilot.app.current is member

    await until(pilot, there)


def test_one_tui_over_two_robots_keys_act_on_the_selected_session(machines: Machines,
                                                                  write, monkeypatch):
    base, arm = start_all(write, (machines["robot1"], "base", 0), (machines["robot2"], "arm", 1))
    # robot1's link comes back only when asked (R), so what follows surely happens while
    # it is down
    monkeypatch.setattr(remote_supervisor, "RETRY_FIRST", 600.0)

    async def watched() -> None:
        app = FleetApp([("robot1", "base"), ("robot2", "arm")])
        said = notices(app)
        async with app.run_test(size=(100, 30)) as pilot:
            first, second = app.members
            await until(pilot, lambda: ticks(first) >= 3 and ticks(second) >= 3)
            for member, label in ((first, "robot1:base"), (second, "robot2:arm")):
                root = str(member.tree.root.label)
                assert root.startswith(label) and "2 running" in root, root

            # r on robot1's ticker restarts it there, and nothing on robot2
            await select(pilot, first, "ticker-1")
            assert "[robot1:base]" in str(app.status_bar.render())
            await pilot.press("r")
            await until(pilot, lambda: starts(first, "ticker-1") == 2 and
                        first.supervisor.states["ticker-1"] == "running")
            # s, then t, on robot1's quiet: stopped and started there
            await select(pilot, first, "quiet-2")
            await pilot.press("s")
            await until(pilot, lambda: first.supervisor.states["quiet-2"] == "exited")
            assert second.supervisor.states["quiet-2"] == "running"
            await pilot.press("t")
            await until(pilot, lambda: first.supervisor.states["quiet-2"] == "running" and
                        starts(first, "quiet-2") == 2,
                        explain=lambda: f"states {first.supervisor.states}, "
                        f"{starts(first, 'quiet-2')} starts, said {said}, pane "
                        f"{[line.text for line in first.store.lines(View('quiet-2'))]}")
            # s on robot2's quiet stops it there, and nothing on robot1
            await select(pilot, second, "quiet-2")
            assert "[robot2:arm]" in str(app.status_bar.render())  # the header follows
            await pilot.press("s")
            await until(pilot, lambda: "1 running  1 exited" in str(second.tree.root.label))
            assert second.supervisor.states["quiet-2"] == "exited"
            assert first.supervisor.states == {"ticker-1": "running", "quiet-2": "running"}
            assert starts(second, "ticker-1") == 1

            # robot1's link cut: its root greyed with why; its keys refused in one line
            for pid in proxies_on(machines["robot1"]):
                os.kill(pid, signal.SIGKILL)
            await until(pilot, lambda: "link to robot1 lost" in str(first.tree.root.label))
            assert "reconnecting" in str(first.tree.root.label)
            await select(pilot, first, "quiet-2")
            await pilot.press("s")
            await until(pilot, lambda: any(s.startswith("robot1:base: link to robot1 lost")
                                           for s in said))
            # robot2 is live all along: its quiet starts again with t
            await select(pilot, second, "quiet-2")
            await pilot.press("t")
            await until(pilot, lambda: second.supervisor.states["quiet-2"] == "running" and
                        starts(second, "quiet-2") == 2)
            assert "link to robot1 lost" in str(first.tree.root.label)  # still down
            # R brings robot1 back, with what it printed meanwhile
            before = ticks(first)
            await select(pilot, first, "ticker-1")
            await pilot.press("R")
            await until(pilot, lambda: first.supervisor.link_lost is None and
                        ticks(first) > before + 3)
            assert "2 running" in str(first.tree.root.label)
            # T: the time column of robot1's pane, its ROS stamps read over its link
            await pilot.press("T")
            await until(pilot, lambda: any(
                re.match(r"\d\d:\d\d:\d\d\.\d{3} .*tick \d+$", row)
                for row in first.pane.line_view.visible_text()))
            # q leaves both sessions running
            await pilot.press("q")
            await until(pilot, lambda: app.detached)

    asyncio.run(watched())
    addresses = ("robot1:base", "robot2:arm")
    answers = run_cli_together(*(("status", address, "--json") for address in addresses))
    states = {address: {p["id"]: p["state"] for p in json.loads(done.stdout)["processes"]}
              for address, done in zip(addresses, answers, strict=True)}
    assert states == {"robot1:base": {"ticker-1": "running", "quiet-2": "running"},
                      "robot2:arm": {"ticker-1": "running", "quiet-2": "running"}}
    assert run_cli("stop", "robot1:base", "robot2:arm").returncode == 0
    wait_for(lambda: not alive(base) and not alive(arm))


def test_a_robot_unreachable_at_start_is_a_retrying_root_and_the_others_open(
        machines: Machines, write):
    start(machines["robot2"], write, "arm", 1)
    with_gone_host(machines)

    async def watched() -> None:
        app = FleetApp([("gone", "base"), ("robot2", "arm")])
        async with app.run_test(size=(100, 30)) as pilot:
            gone, second = app.members
            await until(pilot, lambda: ticks(second) >= 3 and
                        "cannot reach gone" in str(gone.tree.root.label))
            assert "retrying" in str(gone.tree.root.label)
            assert gone.supervisor is None
            await pilot.press("question_mark")  # the keys, as the fleet binds them
            await until(pilot, lambda: isinstance(app.screen, FleetHelp))
            assert "Restart the selected node" in str(app.screen.query_one(Static).render())
            await pilot.press("escape")
            await until(pilot, lambda: not isinstance(app.screen, FleetHelp))
            await select(pilot, second, "ticker-1")
            await pilot.press("r")
            await until(pilot, lambda: starts(second, "ticker-1") == 2)
            # robot2's session stopped from a shell: its root says it ended; the TUI
            # stays for the robot it still waits for
            stopped = run_cli("stop", "robot2:arm")
            assert stopped.returncode == 0, stopped.stderr
            await until(pilot, lambda: "ended" in str(second.tree.root.label))
            assert "2 exited" in str(second.tree.root.label) or second.ended
            assert app.is_running and "retrying" in str(gone.tree.root.label)
            await pilot.press("q")

    asyncio.run(watched())


def test_attach_of_two_sessions_on_a_terminal(machines: Machines, write):
    start_all(write, (machines["robot1"], "base", 0), (machines["robot2"], "arm", 1))
    # `attach --type`: the session's TUI typing into the node (one run with pipes, as
    # here, is offered a terminal first: n leaves it as it is)
    single = Terminal("attach", "robot1:base", "--type", "quiet-2")
    try:
        single.read_until(b"quiet-2 has no terminal")
        # the question takes a key typed once it shows (an n in the burst that opened it is
        # dropped with it), and the keys after its n are the node's: n and d again, every
        # half second, until n has answered and d has detached
        assert single.press_until_exit(b"nd") == 0
    finally:
        single.close()
    wrong = Terminal("attach", "robot1:base", "--type", "nosuch")  # one line, no TUI
    try:
        assert wrong.wait_exit() == 2
        assert b"tuilaunch attach: error: session robot1:base: no process 'nosuch'" in \
            wrong.screen
    finally:
        wrong.close()
    terminal = Terminal("attach", "robot1:base", "robot2:")
    try:
        for marker in (b"robot1:base", b"robot2:arm", b"tick"):
            terminal.read_until(marker)
        # a burst as ssh delivers it: the Services tab, its filter, a term; none of its
        # letters is a fleet key (s stops, t starts) on its way to the field
        os.write(terminal.master, b"3/stop")
        terminal.read_until(b"stop")
        os.write(terminal.master, b"\x1b1")  # out of the field, back to the trees
        terminal.read_until(b"1 Nodes")
        assert b"Stop all" not in terminal.screen
        os.write(terminal.master, b"q")
        assert terminal.wait_exit() == 0
        assert b"detached; the sessions run on: tuilaunch attach robot1:base robot2:arm" \
            in terminal.screen
    finally:
        terminal.close()
    for address in ("robot1:base", "robot2:arm"):  # the burst stopped nothing
        states = {p["id"]: p["state"] for p in json.loads(
            run_cli("status", address, "--json").stdout)["processes"]}
        assert states == {"ticker-1": "running", "quiet-2": "running"}, address
    assert run_cli("stop", "robot1:", "robot2:").returncode == 0


@pytest.mark.usefixtures("runtime")  # a private session folder
def test_lifecycle_keys_step_the_selected_sessions_node_and_no_other(write):
    """`]` and `[` in the fleet view, on two local sessions each with a lifecycle node: the
    selected session's node steps (`[[` down to unconfigured, `]]` back up to active, typed
    faster than it moves), the other session's stays active; where no step goes, one line;
    `c` shows the node's command line, `g` restarts it under a tool, `i` types into it in
    the fleet view."""
    first, _ = detached_with(str(write(LIFECYCLE, "one.py")), "lc-1")
    second, _ = detached_with(str(write(LIFECYCLE.replace("name='lc'", "name='lc2'"),
                                        "two.py")), "lc2-1")

    async def watched() -> None:
        app = FleetApp([(None, first), (None, second)])
        said = notices(app)
        async with app.run_test(size=(100, 30)) as pilot:
            one, two = app.members

            def state(member: SessionView, process: str) -> str | None:
                return None if member.supervisor is None else \
                    member.supervisor.lifecycle.states.get(process)

            await until(pilot, lambda: state(one, "lc-1") == "active"
                        and state(two, "lc2-1") == "active")
            await select(pilot, one, "lc-1")
            await pilot.press("left_square_bracket", "left_square_bracket")
            await until(pilot, lambda: state(one, "lc-1") == "unconfigured")
            await until(pilot, lambda: "· unconfigured" in str(one.tree.rows["lc-1"].label))
            await pilot.press("right_square_bracket", "right_square_bracket")
            await until(pilot, lambda: state(one, "lc-1") == "active")
            assert state(two, "lc2-1") == "active"  # the other robot's node: untouched
            assert not [s for s in said if "refused" in s or "lc-1" in s]
            # nothing above active: one line, no step
            await until(pilot, lambda: "· active" in str(one.tree.rows["lc-1"].label))
            await pilot.press("right_square_bracket")
            await until(pilot, lambda: any(s.startswith("local:one-1: lc-1 is active: no step up")
                                           for s in said))
            # c: the selected node's command line, as its session started it
            await pilot.press("c")
            await until(pilot, lambda: isinstance(app.screen, CommandScreen))
            assert "lifecycle_talker" in app.screen.line and "__node:=lc" in app.screen.line
            await pilot.press("escape")
            # g: restarted under a tool there, the other robot's node untouched
            await pilot.press("g")
            await until(pilot, lambda: isinstance(app.screen, PrefixPrompt))
            await pilot.press(*"nice", "enter")
            await until(pilot, lambda: any("lc-1 runs under nice" in s for s in said))
            await until(pilot, lambda: state(one, "lc-1") == "active")
            # i: typing into the node right here (no other TUI: a browser's page cannot
            # run one); under its tool it has a terminal, and the s typed with the i is
            # the node's, never a stop; ctrl+] gives the keys back
            app.post_message(events.Key("i", "i"))
            app.post_message(events.Key("s", "s"))
            await until(pilot, lambda: one.keyboard.typing_to == "lc-1")
            await until(pilot, lambda: one.keyboard.typed_line == "s")
            await pilot.press("ctrl+right_square_bracket")
            await until(pilot, lambda: one.keyboard.typing_to is None)
            for _ in range(5):
                await pilot.pause(0.05)
            assert one.supervisor.states["lc-1"] == "running"
            assert not [s for s in said if "refused" in s or "not sent" in s]
            await pilot.press("q")
            await until(pilot, lambda: app.detached)

    asyncio.run(watched())
    command = next(p for p in json.loads(tl("status", first, "--json").stdout)["processes"]
                   if p["id"] == "lc-1")["command_line"]
    assert " nice /" in command  # after the environment launch gives it
    other = next(p for p in json.loads(tl("status", second, "--json").stdout)["processes"]
                 if p["id"] == "lc2-1")["command_line"]
    assert " nice " not in other
    for name, process in ((first, "lc-1"), (second, "lc2-1")):
        assert tl("status", name, "--json").returncode == 0
        tl("wait", name, process, "running", "--timeout", "30")  # q left both running


@pytest.mark.usefixtures("runtime")  # a private session folder
def test_services_params_and_topics_tabs_follow_the_selected_session(write):
    """Two robots' launches on two ROS domains: 3, 4 and 5 in the fleet view show the
    services, the nodes' parameters and the topics of the session of the selected row, each
    robot's own graph; a Nodes key does nothing there; `/` goes into the tab's filter."""
    bringup = str(Path(__file__).parents[2] / "examples" / "bringup.py")
    names = []
    for robot, offset in (("ra", 0), ("rb", 1)):
        done = run_cli(bringup, "--detach", "--name", robot, f"robot:={robot}",
                       "listener:=false", env={**os.environ, "ROS_DOMAIN_ID": domain(offset)})
        assert done.returncode == 0, done.stderr
        names.append(robot)
    for robot in names:
        tl("wait", robot, "service_server-4", "running", "--timeout", "60")

    async def watched() -> None:
        app = FleetApp([(None, "ra"), (None, "rb")])
        async with app.run_test(size=(100, 30)) as pilot:
            ra, rb = app.members
            await until(pilot, lambda: ra.supervisor is not None and rb.supervisor is not None)
            panels = {m.label: app.session_tabs.of(m) for m in app.members}

            def services(member: SessionView) -> list[str]:
                return [name for name, _ in panels[member.label].services.services]

            await select(pilot, ra, "talker-1")
            await pilot.press("3")
            assert app.tabs.active == "services"
            await until(pilot, lambda: "/ra/reset" in services(ra))
            assert not [s for s in services(ra) if s.startswith("/rb/")]
            assert "[local:ra]" in str(app.status_bar.render())
            # a Nodes key does nothing here: the talker runs on
            await pilot.press("s")
            assert ra.supervisor.states["talker-1"] == "running"
            # / into this tab's filter, escape back to its list
            await pilot.press("slash")
            assert app.focused is panels["local:ra"].services.query_one("#svc-filter")
            await pilot.press("escape")
            assert app.focused is panels["local:ra"].services.query_one("#svc-list")

            # the other robot: its own services, parameters and topics
            await pilot.press("1")
            await select(pilot, rb, "talker-1")
            await pilot.press("3")
            await until(pilot, lambda: "/rb/reset" in services(rb))
            assert not [s for s in services(rb) if s.startswith("/ra/")]
            assert "[local:rb]" in str(app.status_bar.render())
            await pilot.press("4")
            params = panels["local:rb"].params
            await until(pilot, lambda: "/rb/talker" in params.nodes)
            assert not [n for n in params.nodes if n.startswith("/ra/")]
            await pilot.press("5")
            topics = panels["local:rb"].topics
            await until(pilot, lambda: "/rb/chatter" in topics.entries)
            assert "/ra/chatter" not in topics.entries
            await until(pilot, lambda: (topics.rates.get("/rb/chatter") or {}).get("rate_hz"))
            assert topics.active and not panels["local:ra"].topics.active
            # o on rb's talker: its topics only, in its Topics tab
            await pilot.press("1")
            await select(pilot, rb, "talker-1")
            await pilot.press("o")
            assert app.tabs.active == "topics" and topics.node == "/rb/talker"
            await until(pilot, lambda: "/rb/chatter" in topics.entries)

            # 2 on ra: its form; an edit and F5 relaunch ra alone
            await pilot.press("1")
            await select(pilot, ra, "talker-1")
            await pilot.press("2")
            form = panels["local:ra"].args
            await until(pilot, lambda: form.query("#arg-rate"))
            assert form.query_one("#arg-robot", Input).value == "ra"
            form.query_one("#arg-rate", Input).value = "5.0"  # as typed
            await until(pilot, lambda: form.preview is not None)
            await pilot.press("f5")
            await until(pilot, lambda: ra.session.arguments.get("rate") == "5.0"
                        and starts(ra, "talker-1") == 2)
            assert "Applied." in str(form.query_one("#args-preview", Static).render())
            assert rb.session.arguments.get("rate") != "5.0" and starts(rb, "talker-1") == 1
            # L on rb's talker: no logger service in the demo's nodes, so a restart at
            # that level is offered, there only
            await pilot.press("1")
            await select(pilot, rb, "talker-1")
            await pilot.press("L")
            await until(pilot, lambda: isinstance(app.screen, ChoiceScreen))
            await pilot.press("d")
            await until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
            assert "talker has no logger service" in str(app.screen.question)
            await pilot.press("y")
            await until(pilot, lambda: starts(rb, "talker-1") == 2)
            assert starts(ra, "talker-1") == 2  # ra's: only its F5's restart
            await pilot.press("q")
            await until(pilot, lambda: app.detached)

    asyncio.run(watched())
    assert tl("status", "ra", "--json").returncode == 0
    assert json.loads(tl("status", "ra", "--json").stdout)["arguments"]["rate"] == "5.0"
    talker = json.loads(tl("status", "rb", "--json").stdout)["processes"][0]
    assert "--log-level debug" in talker["command_line"]
    for robot in names:
        tl("stop", robot)
