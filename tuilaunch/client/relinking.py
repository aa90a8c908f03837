"""A dropped ssh link to a session on another machine, reconnected: the attempts with
backoff (the client's Reconnector), each new reason said once, and on success what
happened meanwhile delivered (the client's `catch_up`: the log files' lines and the state
events the server kept, from where its view stood). The launch there runs on meanwhile.

A function over a small host interface (`LinkedClient`, which RemoteSupervisor is) rather
than a part of that class: the reconnection is a concern of its own, which a session on
this machine never has.
"""

from __future__ import annotations

import asyncio
from typing import Protocol

from ..engine.run.events import Event
from ..engine.run.machines.proxy import SERVER_GONE_WORDS
from ..engine.run.machines.remote import RemoteError, RemoteLink, open_remote_connection
from ..engine.run.session.connection import Connection
from ..engine.run.session.protocol import ProtocolError, VersionMismatch
from ..engine.run.session.reconnector import Reconnector
from ..engine.run.session.session_dir import SessionError
from .gaps import Gaps
from .inspect.watches import Watches
from .link import ANSWER_TIMEOUT
from .session_state import SessionState


async def ssh_connection(host: str, name: str, link: RemoteLink | None = None,
                         ) -> tuple[RemoteLink, Connection]:
    """A Connection over an ssh link to `host`'s session (`link`: one already open and
    greeted, else a new one; RemoteError with one line when it cannot be made)."""
    if link is None:
        return await open_remote_connection(host, name)
    return link, await Connection.on_socket(link.sock, link.info, f"{host}:{name}")


class LinkedClient(Protocol):
    """What a reconnection is handed of the client whose link dropped."""

    name: str
    link: RemoteLink | None
    conn: Connection
    relink: Reconnector
    state: SessionState
    gaps: Gaps
    watches: Watches
    detached: bool  # the client left: give up
    stopping: bool  # it asked the session to stop: its end is no loss
    lost: bool  # set: the session ended unseen, or its server died

    async def catch_up(self) -> list[Event]:
        """Subscribed again on `conn`: what happened while the link was down."""
        ...


async def relink(client: LinkedClient, host: str, first: float) -> bool:
    """The link to `host` dropped: reconnect with backoff (`first`: the first wait), then
    deliver what was missed. False when there is nothing to reconnect to (detached, or the
    session ended)."""
    assert client.link is not None
    loop = asyncio.get_running_loop()
    say = client.state.say
    client.conn.close()
    why = await loop.run_in_executor(None, client.link.why_lost)
    if SERVER_GONE_WORDS in why:
        # the link was up: the proxy there saw the session's server die (kill -9)
        client.lost = not client.stopping
        say(f"{host}: {why.split('error: ', 1)[-1]}", "ERROR")
        return False
    client.relink.lost(f"link to {host} lost ({why})", why, first)
    client.conn.fail(f"link to {host} lost ({why})")
    say(f"{client.relink.down}; session {client.name} runs on there; reconnecting", "ERROR")
    while not client.detached:
        await client.relink.next_attempt()
        if client.detached:
            return False
        try:
            link, client.conn = await ssh_connection(host, client.name)
        except VersionMismatch as exc:
            # another session of that name, of another tuilaunch: not ours to speak to
            client.relink.down = None
            say(str(exc), "ERROR")
            return False
        except RemoteError as exc:
            if "no running session" in str(exc):
                client.lost = not client.stopping  # unless it was asked to stop
                client.relink.down = None
                say(f"session {client.name} ended on {host} while the link was down",
                    "ERROR")
                return False
            if client.relink.failed(str(exc)):  # each new reason once, not every try
                say(f"reconnecting: {exc}", "WARN")
            continue
        old, client.link = client.link, link
        await loop.run_in_executor(None, old.close)
        start, received = client.gaps.start, client.gaps.received
        try:
            missed = await asyncio.wait_for(client.catch_up(), ANSWER_TIMEOUT * 3)
            await asyncio.wait_for(client.watches.ask_again(
                client.conn.call, lambda text: say(text, "WARN")), ANSWER_TIMEOUT * 3)
        except (TimeoutError, ConnectionError, ProtocolError, SessionError) as exc:
            # the link dropped again before the gap was read: it is read on the next
            # one, from the same place; what this one sent meanwhile is in that gap
            client.gaps.start, client.gaps.received = start, received
            client.conn.forget_early()
            client.conn.close()
            say(f"reconnecting: {exc}", "WARN")
            continue
        client.relink.back()
        say(f"link to {host} back: what happened meanwhile follows")
        for event in missed:
            client.state.deliver(event)
        return True
    return False
