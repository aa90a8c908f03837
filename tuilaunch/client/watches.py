"""The inspector's streams a client asked a session server for (rates, echo, plots, CPU
and memory, QoS marks), as the requests that asked: a stream ends with the connection that
carried it, so a client's new connection (a dropped ssh link, reconnected) asks again."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from ..engine.run.session.session_dir import SessionError


class Watches:
    """The streams running for one client, kept as their requests."""

    def __init__(self) -> None:
        self.asked: dict[str, dict[str, Any]] = {}

    def note(self, op: str, fields: dict[str, Any]) -> None:
        """A request that went through: a stream it starts is kept, one it ends dropped."""
        if op == "watch_rates":
            key = op
            on = bool(fields.get("topics"))
        elif op in ("echo", "echo_stop"):
            key, on = f"echo {fields.get('topic')}", op == "echo"
        elif op in ("plot", "plot_stop"):
            key, on = f"plot {fields.get('topic')}", op == "plot"
        elif op in ("watch_resources", "watch_qos"):
            key, on = op, bool(fields.get("on", True))
        else:
            return
        if on:
            self.asked[key] = {"op": op, **fields}
        else:
            self.asked.pop(key, None)

    async def ask_again(self, call: Callable[..., Awaitable[Any]],
                        warn: Callable[[str], None]) -> None:
        """On a new connection: each stream asked for again with `call(op, **fields)`; one
        the server refuses now (its topic went away meanwhile, say) is dropped, and said."""
        for key, asked in list(self.asked.items()):
            fields = {k: v for k, v in asked.items() if k != "op"}
            try:
                await call(asked["op"], **fields)
            except SessionError as exc:
                self.asked.pop(key, None)
                warn(f"not watched again: {exc}")
