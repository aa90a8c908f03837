"""The session's plan over the protocol, for a client that cannot read the launch file (a
TUI on an operator's laptop, the file on the robot): `plan` sends the plan the session runs
and its arguments; `preview {arguments, running}` says what those values would do, resolved
here where the file, the packages and the processes are (`file_changes`: the file was
edited on disk, and what the edit alone changes). `apply` then relaunches."""

from __future__ import annotations

from typing import Any

from ...plan.model import Plan
from ...plan.session import Session
from ..plugins import Handlers
from ..vocabulary.requests import GetPlan, PreviewArguments


def plan_message(session: Session, plan: Plan | None = None) -> dict[str, Any]:
    """The plan as JSON with the values it was resolved from."""
    return {"plan": (plan or session.plan).to_json(), "arguments": dict(session.arguments)}


def plan_handlers(session: Session) -> Handlers:
    """The `plan` and `preview` requests, answered from `session` (the server's)."""

    async def plan(request: GetPlan, client: int) -> Any:
        return plan_message(session)

    async def preview(request: PreviewArguments, client: int) -> Any:
        values, running = request.arguments, request.running
        result = session.preview({str(k): str(v) for k, v in values.items()},
                                 None if running is None else {str(p) for p in running})
        if result.plan is None or result.diff is None:
            return {"arguments": result.arguments, "error": result.error}
        diff, edit = result.diff, result.file_changes
        return {"arguments": result.arguments, "plan": result.plan.to_json(),
                "keep": diff.keep, "stop": diff.stop, "start": diff.start, "error": None,
                # the launch file was edited on disk: what the edit alone changes
                "file_changes": None if edit is None else {
                    "keep": edit.keep, "stop": edit.stop, "start": edit.start},
                "edited": result.edited}

    return {GetPlan: plan, PreviewArguments: preview}
