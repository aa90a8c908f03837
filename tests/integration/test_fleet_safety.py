"""The fleet view as safe as the single TUI (issue 46), over two robots through real sshd
"machines" on 127.0.0.1: a stop of a session's root asks first, naming the session; the
cursor never wraps from one robot onto another; `}` and `{` jump between the sessions'
roots; a link that hangs (its far end stopped with SIGSTOP) is marked on its root within
8 s; `p` in Topics plots the topic over the selected session's link.
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from tuilaunch.client import remote_supervisor
from tuilaunch.tui.fleet.app import FleetApp
from tuilaunch.tui.screens.dialogs import ConfirmScreen

from .sshd import Machines, machines_fixture, proxies_on  # noqa: F401
from .test_fleet_cli import started
from .test_fleet_tui import notices
from .test_sessions import runtime  # noqa: F401
from .test_tui import until

SIGNAL_NODE = Path(__file__).resolve().parent / "nodes" / "signal_node.py"
LAUNCH = f"""
from launch import LaunchDescription
from launch.actions import ExecuteProcess
def generate_launch_description():
    return LaunchDescription([
        ExecuteProcess(name='ticker', cmd=[
            'sh', '-c', 'i=0; while true; do i=$((i+1)); echo tick $i; sleep 0.2; done']),
        ExecuteProcess(name='quiet', cmd=['sleep', '600']),
        ExecuteProcess(name='wave', cmd=[{sys.executable!r}, {str(SIGNAL_NODE)!r}, 'wave',
                                         '--topic', '/wave', '--rate', '20']),
    ])
"""


def test_fleet_view_asks_never_wraps_marks_a_hung_link_and_plots(machines: Machines, write,
                                                                 monkeypatch):
    path = write(LAUNCH)
    with ThreadPoolExecutor() as pool:
        list(pool.map(lambda s: started(*s), ((machines["robot1"], path, "base", 0),
                                              (machines["robot2"], path, "arm", 1))))
    # a link that hangs is retried only when asked: what follows happens while it is down
    monkeypatch.setattr(remote_supervisor, "RETRY_FIRST", 600.0)

    async def watched() -> None:
        app = FleetApp([("robot1", "base"), ("robot2", "arm")])
        said = notices(app)
        async with app.run_test(size=(100, 30)) as pilot:
            first, second = app.members
            await until(pilot, lambda: all("3 running" in str(m.tree.root.label)
                                           for m in app.members),
                        explain=lambda: [str(m.tree.root.label) for m in app.members])

            # up on the first session's root: the cursor stays (no wrap onto robot2)
            first.tree.focus()
            first.tree.cursor_line = 0
            await pilot.press("up")
            assert app.current is first and first.tree.cursor_line == 0
            # } jumps to robot2's root, { back to robot1's
            await pilot.press("right_curly_bracket")
            await until(pilot, lambda: app.current is second and second.tree.cursor_line == 0)
            assert "[robot2:arm]" in str(app.status_bar.render())
            await pilot.press("right_curly_bracket")  # the last session: it stays
            assert app.current is second
            # down past robot2's last row: it stays there (no wrap onto robot1)
            second.tree.cursor_line = second.tree.last_line
            await pilot.press("down")
            await pilot.pause()
            assert app.current is second and \
                second.tree.cursor_line == second.tree.last_line
            await pilot.press("left_curly_bracket")
            await until(pilot, lambda: app.current is first and first.tree.cursor_line == 0)

            # s on robot1's root asks first, naming robot1's session; n stops nothing
            await pilot.press("s")
            await until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
            question = app.screen.question  # type: ignore[attr-defined]
            assert question.startswith("Stop all 3 running processes of robot1:base:"), \
                question
            await pilot.press("n")
            await until(pilot, lambda: not isinstance(app.screen, ConfirmScreen))
            # r on robot2's root asks too, naming it
            await pilot.press("right_curly_bracket")
            await until(pilot, lambda: app.current is second)
            await pilot.press("r")
            await until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
            assert "of robot2:arm:" in app.screen.question  # type: ignore[attr-defined]
            await pilot.press("escape")
            await until(pilot, lambda: not isinstance(app.screen, ConfirmScreen))
            for member in app.members:
                assert member.supervisor is not None
                assert set(member.supervisor.states.values()) == {"running"}

            # p on robot2's /wave: the single TUI's plot, over robot2's link
            from tuilaunch.tui.screens.plot_screen import PlotScreen
            from tuilaunch.tui.screens.topics_panel import TopicsPanel
            await pilot.press("5")
            panel = app.session_tabs.of(second).topics
            assert isinstance(panel, TopicsPanel)
            await until(pilot, lambda: "/wave" in panel.shown, limit=90)
            panel.query_one("#tpc-table").move_cursor(  # type: ignore[attr-defined]
                row=panel.shown.index("/wave"))
            await until(pilot, lambda: panel.selected == "/wave")
            await pilot.press("p")
            await until(pilot, lambda: isinstance(app.screen, PlotScreen),
                        explain=lambda: (said, [(w.name, w.state, w.error)
                                                for w in app.workers]))
            plot = app.screen
            assert isinstance(plot, PlotScreen)
            assert [(s.session, s.topic, s.fields) for s in plot.series.sources] == \
                [("robot2:arm", "/wave", ["x"])]  # the first numeric field, of robot2
            await until(pilot, lambda: plot.drawn, limit=60,  # its samples came
                        explain=lambda: said)
            await pilot.press("q")
            await until(pilot, lambda: not isinstance(app.screen, PlotScreen))
            await pilot.press("1")

            # robot1's far end stopped (a link that hangs: no bytes, no error): its root
            # says "no word from robot1" within 8 s; robot2's stays live
            stopped = proxies_on(machines["robot1"])
            assert stopped
            try:
                for pid in stopped:
                    os.kill(pid, signal.SIGSTOP)
                await until(pilot, lambda: "no word from robot1 for"
                            in str(first.tree.root.label), limit=8,
                            explain=lambda: str(first.tree.root.label))
                assert "no word" not in str(second.tree.root.label)
                assert "3 running" in str(second.tree.root.label)
            finally:
                for pid in stopped:
                    os.kill(pid, signal.SIGCONT)
            # once it speaks again the mark goes
            await until(pilot, lambda: "no word" not in str(first.tree.root.label))
            await pilot.press("q")
            await until(pilot, lambda: app.detached)

    asyncio.run(watched())
