"""The operator's hands on one node: `i` types into its terminal until ctrl+] (for a node
started with pipes, as launch's default is, it offers to restart it with a terminal
first), `g` restarts it under a tool (gdb, valgrind...), `c` shows the exact command it was
started with. Through the session's server (one client types at a time).

The keyboard acts on one session through a small host (host.py's KeyboardHost): a session
view (session_view.py), the single TUI's one as each of a fleet's, so `i` types into a
node of any session of a fleet in the fleet's own screen, a browser's page too."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from rich.text import Text
from textual.binding import Binding

from ...client.port import LaunchPort
from ...client.read_only import refusal
from ...engine.errors import LaunchError
from ...engine.run.events import LIVE_STATES, Event, Failed, ProcessExited, Started, Typing
from ...engine.run.vocabulary.requests import Input, Status, TakeKeys
from ...engine.run.vocabulary.status import ProcessStatus
from ..key_order import KeyHold, hold_keys
from ..screens.interact_dialogs import CommandScreen, PrefixPrompt, TerminalQuestion, TypingLine
from ..screens.tree_panel import LaunchTree, RowKind
from .host import KeyboardHost
from .key_bytes import edit_line, is_release, key_bytes

RECENT_PREFIXES = 10
"""Tools remembered for the prompt, most recent first (in memory, for this TUI)."""


KEYBOARD_BINDINGS = [
    Binding("i", "keyboard('type_into')", "Type", tooltip="Send the keys to the node's "
            "terminal until ctrl+] (a node started with pipes is offered a terminal first)"),
    Binding("g", "keyboard('run_under')", "Debug", tooltip="Restart the node under a tool "
            "(gdb, valgrind...) until its next plain restart"),
    Binding("c", "keyboard('command_line')", "Command", show=False,
            tooltip="The exact command line the node was started with, to copy"),
    # where `i` or `g` cannot act (a row that is not a node, a read-only view, a session out
    # of reach), these take the key: the keys typed with it are dropped and one line says
    # why, where they would otherwise run as commands (`istop` Enter on a group stopped it)
    Binding("i", "keyboard('keys_not_here', 'i')", show=False),
    Binding("g", "keyboard('keys_not_here', 'g')", show=False),
]
"""The keyboard's keys, bound on the app (the single TUI's and the fleet's alike:
`action_keyboard` hands them to the NodeKeyboard of the selected session)."""


class NodeKeyboard:
    """Typing into the selected node, running it under a tool, its command line, on one
    session (its `host`, the session's view): an object the view holds (the single TUI's
    `app.keyboard` is its view's), its keys handed to it by name (`act`)."""

    def __init__(self, host: KeyboardHost) -> None:
        self.host = host
        self.typing_to: str | None = None
        """The node the keys go to, while typing."""
        self.typed_line = ""
        """What was typed since the last Enter: shown before the node's echo arrives."""
        self.prefix_history: list[str] = []
        self.other_typists: dict[str, int] = {}
        """Processes another client types into, and that client's number."""
        self._keys_out: list[str] = []
        self._coming_back: set[str] = set()
        """Processes whose end said `again` (a restart, a relaunch) and that have not started
        since: over a session the restart's reply can come before its events."""
        self._sending = False
        self._typing_line: TypingLine | None = None

    # --- which keys apply -----------------------------------------------------------------

    def applies(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """As Textual's check_action for the keyboard's keys (`action` its name here)."""
        host = self.host
        if action in ("type_into", "run_under", "command_line"):
            if host.supervisor is None or not host.nodes_shown():
                return False
            if action != "command_line" and (host.read_only or
                                              host.unavailable() is not None):
                return False  # a footer offers nothing it refuses (keys_not_here says why)
            return True if host.selected_process() else None
        # keys_not_here: reached only when the key's own action cannot run
        return host.nodes_shown()

    def act(self, action: str, *parameters: str) -> None:
        {"type_into": self.type_into, "run_under": self.run_under,
         "command_line": self.command_line,
         "keys_not_here": lambda: self.keys_not_here(*parameters),
         # a key a read-only view refuses (s, r, t, F5...): one line, nothing sent
         "refused": lambda: self.host.notify(str(refusal(parameters[0])),
                                             severity="warning")}[action]()

    def keys_not_here(self, key: str) -> None:
        """`i` or `g` where it cannot act: said at once, and the rest of its burst dropped
        (never commands)."""
        self._refused(hold_keys(self.host.app), self._why_not_here(key), key)

    def _why_not_here(self, key: str) -> str:
        host = self.host
        if host.read_only:
            return refusal("typing into a node" if key == "i" else
                           "running a node under a tool").args[0]
        return host.unavailable() or not_a_node(host.launch_tree, key)

    # --- typing ---------------------------------------------------------------------------

    def type_first(self, process: str) -> None:
        """`attach --type`: the process's row selected and typed into, as `i` on it."""
        tree = self.host.launch_tree
        if process in tree.rows:
            tree.move_cursor(tree.rows[process])
            self.type_into()

    def type_into(self) -> None:
        process = self.host.selected_process()
        if process is None or self.host.supervisor is None:
            return
        # the keys typed right after `i` are for the node (they wait for its typing line),
        # or answer the question whether to give it a terminal
        hold = hold_keys(self.host.app)
        self.host.app.run_worker(self._take_keyboard(process, hold), group="typing",
                                 exit_on_error=False)

    async def _take_keyboard(self, process: str, hold: KeyHold) -> None:
        """Types into the node, or offers what would let `i` type (a terminal, a start);
        where nothing can, the keys typed with `i` are dropped: a key typed for a node
        never becomes one of tuilaunch's commands (`s` stop, `q` quit, `d` detach)."""
        host = self.host
        supervisor = host.supervisor
        assert supervisor is not None
        state = supervisor.states.get(process)
        try:
            terminal = await host.engine.run(had_terminal(supervisor, process)) \
                if state in RAN else None
        except LaunchError as exc:
            self._refused(hold, str(exc))
            return
        if terminal is False or state in ("exited", "failed"):
            self._offer_terminal(process, "Restart" if state == "running" else "Start",
                                 piped=terminal is False)
            # the question waits for a key typed once it is shown: the keys typed with
            # `i` were for the node, and a `y` among them (`iyes`) must not answer it
            hold.drop(said=lambda: host.notify(
                "The keys typed with i were not sent: answer the question with a key "
                "typed now", severity="warning"))
        elif state != "running":
            self._refused(hold, f"{process} is not running ({state}): there is nothing to "
                          "type into")
        else:
            await self._start_typing(process, hold)

    def _refused(self, hold: KeyHold, why: str, key: str = "i") -> None:
        """`key` (i, g) cannot act: the keys typed with it are dropped with the rest of
        their burst (a key typed for a node never becomes a command: `istop` on a group
        stops nothing), and one line says why."""
        hold.drop()
        self.host.notify(f"{why}. The keys typed with {key} were not sent",
                         severity="warning")

    async def _start_typing(self, process: str, hold: KeyHold) -> None:
        host = self.host
        try:
            await host.engine.run(take_keyboard(host.client(), process))
        except LaunchError as exc:
            self._refused(hold, str(exc))  # another client types into it, it just ended
            return
        except BaseException:
            hold.drop()
            raise
        try:
            self.typing_to = process
            self.typed_line = ""
            line = TypingLine(self._typed, id="typing-line")
            self._typing_line = line
            await host.show_typing_line(line)
            host.app.screen.set_focus(line)
        finally:
            hold.release()  # the keys typed after `i` go to the line
        self._show_typing()
        host.app.refresh_bindings()

    def _offer_terminal(self, process: str, verb: str, piped: bool) -> None:
        """Asks to start (or restart) the node with a terminal; `y` does it and types."""
        def answered(yes: bool | None) -> None:
            if yes:
                # the keys typed after `y` (held since it was answered) are the node's:
                # they wait out the restart (a node slow to stop takes seconds) for its
                # typing line, where tuilaunch's own keys would otherwise get them
                self.host.app.run_worker(
                    self._restart_with_terminal(process, question.hold), group="typing",
                    exit_on_error=False)
            else:
                question.hold.drop()  # no: the rest of the burst was for the node too

        supervisor = self.host.supervisor
        assert supervisor is not None
        who = self._named(process)
        if piped:
            why = (f"{who} has no terminal to type into: its file gives it pipes, as "
                   "ros2 launch does without emulate_tty=True.")
        else:
            why = f"{who} is not running ({supervisor.states.get(process)})."
        question = TerminalQuestion(
            f"{why} {verb} it with a terminal (until its next plain restart) and type "
            "into it?", f"{verb} it (y)")
        self.host.app.push_screen(question, answered)

    def _named(self, process: str) -> str:
        """The process as a question or the typing line names it: in a fleet, with its
        session (`talker-1 of nuc:base`)."""
        return f"{process} of {self.host.who}" if self.host.who else process

    async def _restart_with_terminal(self, process: str, hold: KeyHold) -> None:
        try:
            if await self._restart_with(process, terminal=True):
                await self._start_typing(process, hold)  # the session says if it ended
        finally:
            hold.drop()  # refused, or it ended at once: the keys were the node's

    async def _restart_with(self, process: str, **options: Any) -> bool:
        """Restarts the node with `options` (a tool, a terminal), its stop noted as asked
        for; False, said in one line, when the session refused it."""
        host = self.host
        supervisor = host.supervisor
        assert supervisor is not None
        host.asked_to_stop.add(process)
        try:
            await host.engine.run(supervisor.restart(process, **options))
        except LaunchError as exc:
            host.asked_to_stop.discard(process)
            host.notify(str(exc), severity="error")
            return False
        return True

    def _typed(self, key: str, character: str | None) -> None:
        """A key pressed while typing: to the node, or ctrl+] back to tuilaunch."""
        if self.typing_to is None:
            return
        if key != "paste" and is_release(key, character):
            self.stop_typing()
            return
        data = character if key == "paste" else key_bytes(key, character)
        if not data:
            return
        self.typed_line = edit_line(self.typed_line, data)
        self._keys_out.append(data)
        if not self._sending:
            self._sending = True
            self.host.app.run_worker(self._send_keys(self.typing_to), group="typing-keys",
                                     exit_on_error=False)
        self._show_typing()

    async def _send_keys(self, process: str) -> None:
        """One sender, so keys reach the node in the order they were pressed."""
        try:
            while self._keys_out:
                data = "".join(self._keys_out)
                self._keys_out.clear()
                await self.host.engine.run(type_keys(self.host.client(), process, data))
        except LaunchError as exc:
            self._keys_out.clear()
            self.host.notify(str(exc), severity="error")
        finally:
            self._sending = False

    def stop_typing(self, why: str = "") -> None:
        """Gives the keys back to tuilaunch (and the keyboard to the other clients)."""
        process = self.typing_to
        if process is None:
            return
        host = self.host
        self.typing_to = None
        self.typed_line = ""
        if self._typing_line is not None:
            self._typing_line.remove()
            self._typing_line = None
        host.launch_tree.focus()
        host.app.run_worker(self._release(process), group="typing", exit_on_error=False)
        if why:
            host.notify(why)
        host.update_status()
        host.app.refresh_bindings()

    async def _release(self, process: str) -> None:
        try:
            await self.host.engine.run(release_keyboard(self.host.client(), process))
        except LaunchError:
            pass  # the session is gone, and with it the keyboard

    def _show_typing(self) -> None:
        if self.typing_to is None:
            return
        text = Text.assemble((f"typing to {self._named(self.typing_to)}", "bold"),
                             " (ctrl+] gives the keys back): ", self.typed_line, "▏")
        if self._typing_line is not None:
            self._typing_line.update(text)
        self.host.update_status()

    def status_notes(self, link_lost: bool) -> list[str]:
        """What the status line says before the rest: typing, and who else types where
        (not known while the link is down: the line says that, whole)."""
        notes = [] if link_lost else [f"client {client} types into {process}"
                                      for process, client in self.other_typists.items()]
        if self.typing_to is not None:
            notes.insert(0, f"typing to {self.typing_to}: {self.typed_line}")
        return notes

    def take_events(self, events: list[Event]) -> list[Event]:
        """The keyboard's news in a batch (who types where, restarts under way); the rest,
        for the tabs."""
        rest = []
        for event in events:
            if isinstance(event, (ProcessExited, Started, Failed)) and event.process:
                if isinstance(event, ProcessExited) and (event.data or {}).get("again"):
                    self._coming_back.add(event.process)
                else:
                    self._coming_back.discard(event.process)
            if not isinstance(event, Typing):
                rest.append(event)
                continue
            client = (event.data or {}).get("client")
            process = event.process or ""
            if client is None or process == self.typing_to:
                self.other_typists.pop(process, None)  # ours, or given back
            else:
                self.other_typists[process] = int(client)
        return rest

    def events_shown(self, events: list[Event]) -> None:
        """After a batch: a node stopped to start again keeps the keys (typing began once
        its restart with a terminal was answered, and the news of its stop may come only
        now); one that ended gives them back."""
        supervisor = self.host.supervisor
        if self.typing_to is not None and supervisor is not None and \
                supervisor.states.get(self.typing_to) not in LIVE_STATES and \
                self.typing_to not in self._coming_back:
            self.stop_typing(f"{self.typing_to} is no longer running: the keys are back")
        elif any(isinstance(e, Typing) for e in events):
            self.host.update_status()

    # --- a tool, the command line ---------------------------------------------------------

    def run_under(self) -> None:
        process = self.host.selected_process()
        if process is None:
            return

        def chosen(prefix: str | None) -> None:
            if prefix:  # cancelled: nothing changes
                self.host.app.run_worker(self._restart_under(process, prefix),
                                         group="commands", exit_on_error=False)

        self.host.app.push_screen(PrefixPrompt(process, self.prefix_history), chosen)

    async def _restart_under(self, process: str, prefix: str) -> None:
        if not await self._restart_with(process, prefix=prefix):
            return
        self.prefix_history = remembered(self.prefix_history, prefix)
        self.host.notify(f"{process} runs under {prefix}: i types into it; r restarts it "
                         "plain")

    def command_line(self) -> None:
        process = self.host.selected_process()
        if process is not None:
            # `c y` typed together copies the command: the y waits for its dialog
            release = hold_keys(self.host.app)
            self.host.app.run_worker(self._show_command(process, release), group="commands",
                                     exit_on_error=False)

    async def _show_command(self, process: str, release: Callable[[], None]) -> None:
        """The process's exact command line in a dialog, or one line saying why not."""
        host = self.host
        try:
            status = await host.engine.run(command_of(host.client(), process))
            line = None if status is None else status.command_line
            if line:
                host.app.push_screen(CommandScreen(process, line))
            else:
                host.notify(f"{process} has no command line (it could not be resolved)",
                            severity="warning")
        except LaunchError as exc:  # not following the session yet, a link lost
            host.notify(str(exc), severity="error")
        finally:
            release()  # after the dialog is pushed: the keys held go to it


def not_a_node(tree: LaunchTree, key: str) -> str:
    """Why `i` or `g` cannot act on the tree's selected row (a group, an action, the
    launch: a fleet's session), in one line."""
    node = tree.cursor_node
    kind = node.data.kind if node is not None and node.data is not None else RowKind.GROUP
    label = str(node.label) if node is not None else ""
    label = label if len(label) <= 40 else label[:39] + "…"
    what = {RowKind.ALL: "every node's output", RowKind.ACTION: "an action",
            RowKind.COMPONENT: "a component (its container is the process)"}.get(
                kind, "the launch" if node is tree.root else "a group")
    verb = "types into" if key == "i" else "runs under a tool"
    return f"{label!r} is {what}, not a node: {key} {verb} a node (select its row)"


def remembered(history: list[str], prefix: str) -> list[str]:
    """The tools the prompt offers, `prefix` first."""
    return [prefix, *[p for p in history if p != prefix]][:RECENT_PREFIXES]


# --- the calls on the session's server ----------------------------------------------------

async def take_keyboard(supervisor: LaunchPort, process: str) -> None:
    await supervisor.request(TakeKeys(process=process, on=True))


RAN = ("running", "exited", "failed")
"""States of a process that was started: whether it had a terminal is known."""


async def had_terminal(supervisor: LaunchPort, process: str) -> bool | None:
    """Whether the process's last start gave it a terminal; None when that is not known
    here (run by another machine: taking its keyboard says what it can)."""
    status = await command_of(supervisor, process)
    return None if status is None else status.terminal


async def release_keyboard(supervisor: LaunchPort, process: str) -> None:
    await supervisor.request(TakeKeys(process=process, on=False))


async def type_keys(supervisor: LaunchPort, process: str, data: str) -> None:
    await supervisor.request(Input(process=process, data=data))


async def command_of(supervisor: LaunchPort, process: str) -> ProcessStatus | None:
    """The process as the session's status says it, with its command (None: no such)."""
    return (await supervisor.request(Status(resources=False))).process(process)
