"""`--read-only` (`tuilaunch serve --read-only`, `tuilaunch attach --read-only`): a client of
a real session that changes nothing. Each change the TUI can ask for is refused by the
client with one line, and the session's processes are left as they were; what only reads
still works; q leaves without a question, the launch running on.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from tuilaunch.client.read_only import ReadOnlyError
from tuilaunch.engine.run.vocabulary.request import REQUESTS, from_message
from tuilaunch.engine.run.vocabulary.requests import Find
from tuilaunch.tui.app import make_app

from .test_sessions import LAUNCH, pids, runtime, start_detached, status  # noqa: F401
from .test_tui import until


def test_a_read_only_client_refuses_every_change_with_one_line(runtime, write):  # noqa: F811
    name = start_detached(write)
    log_dir = Path(status(name)["log_dir"])
    before = pids(name)

    async def view() -> None:
        app = make_app(str(write(LAUNCH)), {}, log_dir, session_name=name, read_only=True)
        async with app.run_test(size=(100, 30)) as pilot:
            supervisor = app.supervisor
            assert supervisor is not None and supervisor.read_only
            assert f"[{name} read-only]" in str(app.status_bar.render())
            await pilot.press("down", "down")
            await until(pilot, lambda: app.nodes.commands.selected() == ["ticker-1"])
            said = []
            for key, what in (("s", "stopping"), ("r", "restarting")):
                await pilot.press(key)
                refusal = f"read-only view: {what} a process is refused"
                await until(pilot, lambda r=refusal: r in [n.message for n in
                                                           app._notifications])
                said.append(refusal)
            assert all("\n" not in text for text in said)  # one line each
            # every request that changes something, as the tabs and dialogs send them
            for kind in REQUESTS.values():
                if kind.changes is None:
                    continue
                asked = from_message({"op": kind.op, "process": "ticker-1", "action": "a",
                                      "arguments": {}, "transition": "configure",
                                      "data": "x", "node": "/ticker", "level": "info",
                                      "yaml": "", "service": "/s", "type": "t",
                                      "values": {"x": 1}})
                with pytest.raises(ReadOnlyError):
                    await app.engine.run(supervisor.request(asked))
            # the Params and Services tabs (through the session): nothing set, nothing called
            graph = app.inspector.graph
            with pytest.raises(ReadOnlyError, match="setting a parameter is refused"):
                await app.engine.run(graph.set_parameters("/ticker", {"x": 1}))
            with pytest.raises(ReadOnlyError, match="calling a service is refused"):
                await app.engine.run(graph.call_service("/reset", {}))
            # reading goes through
            found = await app.engine.run(supervisor.request(Find(process="echo-3")))
            assert found == "echo-3"
            assert status(name)["counts"] == {"running": 2, "exited": 1}
            await pilot.press("q")  # leaves, no question: nothing is stopped
            await until(pilot, lambda: app.detached)
        assert app.detached

    asyncio.run(view())
    assert pids(name) == before  # the very same processes, none stopped or restarted
