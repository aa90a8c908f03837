"""The TUI's hands on a node, attached to a real session as `tuilaunch FILE` runs it: `i`
types every key into the node's terminal (ctrl+c too, which must not quit) until ctrl+]
gives them back; `g` restarts a node under a tool from a prompt; `c` shows its command."""

from __future__ import annotations

import asyncio
import time

import pytest
from textual.widgets import Input

from tuilaunch.tui.app import make_app
from tuilaunch.tui.output_store import View
from tuilaunch.tui.screens.dialogs import ConfirmScreen
from tuilaunch.tui.screens.interact_dialogs import CommandScreen, PrefixPrompt

from .session_steps import stop_here
from .test_interact import LAUNCH, PIPED, logs, process
from .test_sessions import detached_with, runtime, status, tl  # noqa: F401  (runtime: a fixture)
from .test_tui import launched, until
from .test_tui_keys import burst

pytestmark = pytest.mark.usefixtures("runtime")  # a private session folder per test


async def select(pilot, app, process_id: str) -> None:
    """The row of `process_id` selected, as the arrows would; again while a row drawn
    afresh (a state just changed on a loaded machine) puts the cursor elsewhere."""
    tree = app.launch_tree

    def there() -> bool:
        node = tree.cursor_node
        if node is None or node.data is None or node.data.ref != process_id:
            tree.move_cursor(tree.rows[process_id])
            return False
        return True

    await until(pilot, there)


def pane(app, process_id: str) -> str:
    return "\n".join(line.text for line in app.store.lines(View(process_id)))


async def terminal_offered(pilot, app, process_id: str) -> str:
    """`i` on a node started with pipes: the question it asks."""
    await select(pilot, app, process_id)
    await pilot.pause()
    await pilot.press("i")
    await until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
    # the question takes a key typed once it shows: after the keys typed with `i`
    await until(pilot, lambda: time.monotonic() >= app.dropping_until)
    return app.screen.question


def test_i_types_into_nodes_until_ctrl_bracket_and_ctrl_c_does_not_quit(write):
    path = str(write(LAUNCH))
    name, log_dir = detached_with(path, "keys-2")

    async def scenario() -> None:
        app = make_app(path, {}, log_dir, session_name=name)
        async with app.run_test(size=(120, 32)) as pilot:
            await until(pilot, lambda: "ready" in pane(app, "lines-1"))
            await until(pilot, lambda: "ready" in pane(app, "keys-2"))
            # `i` on a node that ran with pipes offers a terminal; `n` changes nothing
            await until(pilot, lambda: app.supervisor.states.get("segv-3") == "failed")
            assert "segv-3 has no terminal" in await terminal_offered(pilot, app, "segv-3")
            await pilot.press("n")
            await until(pilot, lambda: not isinstance(app.screen, ConfirmScreen))
            assert app.keyboard.typing_to is None
            assert process(name, "segv-3")["state"] == "failed"
            # no: the rest of n's burst was for the node, and is dropped; the `i` below is
            # a burst of its own, typed after a pause
            await until(pilot, lambda: time.monotonic() >= app.dropping_until)

            await select(pilot, app, "lines-1")
            await pilot.pause()
            await pilot.press("i")
            await until(pilot, lambda: app.keyboard.typing_to == "lines-1")
            await pilot.press(*"hi robot")
            # the partial line shows before the node's echo, which comes at Enter
            assert "typing to lines-1: hi robot" in str(app.status_bar.render())
            await pilot.press("backspace", "enter")
            await until(pilot, lambda: "got: hi robo" in pane(app, "lines-1"))
            assert status(name)["typing"]["process"] == "lines-1"
            await pilot.press("ctrl+right_square_bracket")
            assert app.keyboard.typing_to is None
            await until(pilot, lambda: status(name)["typing"] is None)

            # the raw reader: arrows as escape sequences, ctrl+c as a key, not a quit
            await select(pilot, app, "keys-2")
            await pilot.pause()
            await pilot.press("i")
            await until(pilot, lambda: app.keyboard.typing_to == "keys-2")
            await pilot.press("w", "up", "ctrl+c")
            await until(pilot, lambda: "key: '\\x03'" in pane(app, "keys-2"))
            assert "key: 'w'" in pane(app, "keys-2")
            assert "key: '\\x1b'" in pane(app, "keys-2")  # up: ESC [ A
            assert not app.quitting and app.supervisor.states["keys-2"] == "running"
            await pilot.press("ctrl+right_square_bracket")

            # ctrl+c to the line reader is SIGINT; the keys come back when it ends
            await select(pilot, app, "lines-1")
            await pilot.pause()
            await pilot.press("i")
            await until(pilot, lambda: app.keyboard.typing_to == "lines-1")
            await pilot.press("ctrl+c")
            await until(pilot, lambda: app.supervisor.states.get("lines-1") == "exited")
            await until(pilot, lambda: app.keyboard.typing_to is None)
            assert "interrupted by SIGINT" in logs(name, "lines-1")
            assert not app.quitting
            await pilot.press("d")
            await until(pilot, lambda: getattr(app.supervisor, "detached", False))

    asyncio.run(scenario())
    stop_here(name)


def test_i_on_a_node_started_with_pipes_starts_it_with_a_terminal_and_types_into_it(write):
    """The keyboard node fails with pipes, as teleop_twist_keyboard does under ros2 launch
    without emulate_tty; `i`, then `y` once the question shows, starts it with a terminal
    and the keys go to it. A line typed in the same read as `y` waits out a slow restart and
    goes to the node."""
    path = str(write(PIPED))
    name, log_dir = detached_with(path, "nap-2")

    async def scenario() -> None:
        app = make_app(path, {}, log_dir, session_name=name)
        async with app.run_test(size=(120, 32)) as pilot:
            await until(pilot, lambda: app.supervisor.states.get("lines-1") == "failed")
            await until(pilot, lambda: "stdin is not a terminal" in pane(app, "lines-1"))
            await select(pilot, app, "lines-1")
            await pilot.pause()
            await pilot.press("i")
            await until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
            # a question `i` opens takes a key typed once it shows, after i's burst
            await until(pilot, lambda: time.monotonic() >= app.dropping_until)
            await pilot.press("y")
            await until(pilot, lambda: app.keyboard.typing_to == "lines-1")
            await pilot.press(*"hello", "enter")
            await until(pilot, lambda: "got: hello" in pane(app, "lines-1"))
            await pilot.press("ctrl+right_square_bracket")
            assert app.keyboard.typing_to is None
            assert process(name, "lines-1")["terminal"] is True
            # a node that runs with pipes: the question says restart
            assert "Restart it with a terminal" in await terminal_offered(pilot, app, "nap-2")
            await pilot.press("escape")
            # no: the keys of escape's burst are dropped (they were for the node); the `i`
            # below is a burst of its own, typed after a pause
            await until(pilot, lambda: time.monotonic() >= app.dropping_until)
            # `i y` and a line in one read, as ssh delivers them, to a node that takes a
            # second to stop: the keys after `y` wait out the restart, and are the node's,
            # not tuilaunch's (its `s` would stop the node, its `r` restart it)
            await until(pilot, lambda: "no terminal: waiting" in pane(app, "slow-3"))
            await select(pilot, app, "slow-3")
            await pilot.pause()
            burst(app, "i")
            await until(pilot, lambda: isinstance(app.screen, ConfirmScreen))
            await until(pilot, lambda: time.monotonic() >= app.dropping_until)
            burst(app, "y", *"hello rs", "enter")
            await until(pilot, lambda: "got: hello rs" in pane(app, "slow-3"))
            assert app.keyboard.typing_to == "slow-3"
            assert pane(app, "slow-3").count("stopped slowly") == 1
            await pilot.press("ctrl+right_square_bracket")

    asyncio.run(scenario())
    stop_here(name)


def test_g_prompts_for_a_tool_and_c_shows_the_command_line(write):
    path = str(write(LAUNCH))
    name, log_dir = detached_with(path, "keys-2")
    before = process(name, "keys-2")["pid"]

    async def scenario() -> None:
        app = make_app(path, {}, log_dir, session_name=name)
        async with app.run_test(size=(120, 32)) as pilot:
            await until(pilot, lambda: app.supervisor.states.get("keys-2") == "running")
            await select(pilot, app, "keys-2")
            await pilot.pause()
            # a cancelled prompt changes nothing
            await pilot.press("g")
            await until(pilot, lambda: isinstance(app.screen, PrefixPrompt))
            await pilot.press("escape")
            await until(pilot, lambda: not isinstance(app.screen, PrefixPrompt))
            # a prefix that is not a program: one line, the node runs on untouched
            await pilot.press("g")
            await until(pilot, lambda: isinstance(app.screen, PrefixPrompt))
            app.screen.query_one(Input).value = "no-such-debugger --args"
            await pilot.press("enter")
            await until(pilot, lambda: any("not a program on PATH" in n.message
                                           for n in app._notifications))
            assert process(name, "keys-2")["pid"] == before
            assert app.keyboard.prefix_history == []
            # a real tool: env is on PATH and runs the node as it was
            await pilot.press("g")
            await until(pilot, lambda: isinstance(app.screen, PrefixPrompt))
            app.screen.query_one(Input).value = "env TL_UNDER=1"
            await pilot.press("enter")
            await until(pilot, lambda: app.keyboard.prefix_history == ["env TL_UNDER=1"])
            assert process(name, "keys-2")["command"][:2] == ["env", "TL_UNDER=1"]
            # the prompt remembers it first
            await pilot.press("g")
            await until(pilot, lambda: isinstance(app.screen, PrefixPrompt))
            assert app.screen.choices[0] == "env TL_UNDER=1"
            await pilot.press("escape")
            await until(pilot, lambda: not isinstance(app.screen, PrefixPrompt))
            await pilot.press("c")
            await until(pilot, lambda: isinstance(app.screen, CommandScreen))
            assert "env TL_UNDER=1" in app.screen.line and "raw_key_reader.py" in app.screen.line
            await pilot.press("escape")
            await pilot.press("d")
            await until(pilot, lambda: getattr(app.supervisor, "detached", False))

    asyncio.run(scenario())
    stop_here(name)


async def test_i_types_into_a_node_of_the_tuis_own_launch(tmp_path, write):
    # `tuilaunch FILE`: the TUI that started the session (its owner), the same keys
    async with launched(str(write(LAUNCH)), {}, tmp_path, (120, 32)) as (app, pilot):
        await until(pilot, lambda: "ready" in pane(app, "lines-1"))
        await select(pilot, app, "lines-1")
        await pilot.pause()
        await pilot.press("i")
        await until(pilot, lambda: app.keyboard.typing_to == "lines-1")
        await pilot.press(*"hello", "enter")
        await until(pilot, lambda: "got: hello" in pane(app, "lines-1"))
        await pilot.press("ctrl+right_square_bracket")
        assert app.keyboard.typing_to is None
        await pilot.press("c")
        await until(pilot, lambda: isinstance(app.screen, CommandScreen))
        assert "line_reader.py" in app.screen.line
        await pilot.press("escape")
