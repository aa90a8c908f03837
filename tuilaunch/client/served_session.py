"""`ServedSession`: a Session whose launch file is read by its server, not here.

Attached to another machine's session, the TUI may have no copy of the launch file (it is
on the robot). The server sends the plan it runs (`plan`) and resolves argument edits there
(`preview`), where the file, its packages and the processes are; this class gives the TUI
the Session's interface over those requests."""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Coroutine, Mapping
from pathlib import Path
from typing import Any

from ..engine.plan.model import Plan, PlanDiff, TreeItem
from ..engine.plan.plan_json import plan_from_json
from ..engine.plan.session import Preview, Session
from ..engine.run.vocabulary.requests import PreviewArguments
from .link import ANSWER_TIMEOUT

Requester = Callable[[PreviewArguments], Coroutine[Any, Any, dict[str, Any]]]
"""`await request(PreviewArguments(...))`: the server's result (RemoteSupervisor.request)."""


class ServedSession(Session):
    """The Session interface (plan, arguments, preview, accept) answered by the server;
    RemoteSupervisor asks for the plan again after every relaunch.

    Until `adopt` the plan is empty: the TUI is built before the link is open."""

    def __init__(self, path: str, arguments: Mapping[str, str]) -> None:
        # nothing is loaded here: the file is over there
        self.path = path
        self.placement = None
        self.arguments = dict(arguments)
        self.plan = Plan(path, [], [], [], TreeItem("group", Path(path).name, True), Path())
        self._request: Requester | None = None
        self._loop: asyncio.AbstractEventLoop | None = None

    def connect(self, request: Requester, loop: asyncio.AbstractEventLoop) -> None:
        """Previews are asked with `request`, on `loop` (the engine thread's)."""
        self._request, self._loop = request, loop

    def adopt(self, result: dict[str, Any]) -> None:
        """The server's `plan` reply: the plan it runs and the values it was resolved from."""
        self.plan = plan_from_json(result["plan"])
        self.arguments = {str(k): str(v) for k, v in result["arguments"].items()}

    def preview(self, edits: Mapping[str, str], running: set[str] | None = None,
                reread: bool = False) -> Preview:
        """As Session.preview, resolved by the server (from the UI thread: one round trip)."""
        values = {**self.arguments, **edits}
        if self._request is None or self._loop is None:
            return Preview(values, None, None, "not connected to the session yet")
        asked = self._request(PreviewArguments(
            values, None if running is None else sorted(running)))
        try:
            result: dict[str, Any] = asyncio.run_coroutine_threadsafe(asked, self._loop)\
                .result(ANSWER_TIMEOUT * 3)
        except Exception as exc:  # the link is down, the server refused: said in the form
            return Preview(values, None, None, str(exc) or "the session did not answer")
        if result.get("error") is not None or result.get("plan") is None:
            return Preview(values, None, None, str(result.get("error")))
        edit = result.get("file_changes")
        return Preview(dict(result["arguments"]), plan_from_json(result["plan"]),
                       PlanDiff(list(result["keep"]), list(result["stop"]),
                                list(result["start"])), None,
                       None if edit is None else PlanDiff(list(edit["keep"]),
                                                          list(edit["stop"]),
                                                          list(edit["start"])),
                       edited=result.get("edited"))

    def accept(self, preview: Preview) -> Plan:
        assert preview.plan is not None
        self.arguments = preview.arguments
        self.plan = preview.plan
        return self.plan
