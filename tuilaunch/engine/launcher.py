"""The one place that makes a Supervisor with the ROS plugins wired in.

It sits above both `run` (which knows nothing of ROS) and `ros` (which plugs into `run`),
so the headless mode, the TUI and the session server all get the same launch: the
launch's service calls and parameter sets, lifecycle nodes followed and driven,
components loaded into their containers, and the inspector's session requests (made only
for a launch a session serves, or one whose black box records: a plain `--headless` run has
no client to ask them and does not pay for their classes at start).
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .plan.model import Plan
from .ros.actions import RosActions
from .ros.composition import ComponentLoader
from .ros.lifecycle import LifecycleTracker
from .run.events import Event, Relaunched
from .run.supervisor.supervisor import Supervisor

if TYPE_CHECKING:
    from .plan.machines import Placement
    from .ros.inspector import Inspector
    from .ros.record.recorder import Recorder

BLACK_BOX_ENV = "TUILAUNCH_BLACK_BOX"
"""ros/record/recorder.py's BLACK_BOX_ENV (a test keeps them one), read here without
importing the recorder: set, a launch no session serves still records its black box."""


class RosSupervisor(Supervisor):
    """A Supervisor whose ROS plugins are at hand by name (the TUI asks `lifecycle`)."""

    def __init__(self, plan: Plan, log_dir: Path, sigterm_timeout: float = 5.0,
                 sigkill_timeout: float = 5.0,
                 bridge_factory: Callable[[], Any] | None = None,
                 service_timeout: float = 10.0, served: bool = True) -> None:
        super().__init__(plan, log_dir, sigterm_timeout=sigterm_timeout,
                         sigkill_timeout=sigkill_timeout)
        self.ros = RosActions(bridge_factory, service_timeout, self.emit)
        self.lifecycle = LifecycleTracker(self, self.ros)
        self.components = ComponentLoader(self, self.ros)
        self.add_plugin(self.lifecycle)
        self.add_plugin(self.components)
        # the inspector answers session clients only; the recorder, them and the black box
        self.inspector: Inspector | None = None
        self.recorder: Recorder | None = None
        if served or os.environ.get(BLACK_BOX_ENV):
            from .ros.inspector import Inspector
            from .ros.record.recorder import Recorder

            self.inspector = Inspector(self, self.ros)  # topics, rates, echo, params, loggers
            self.recorder = Recorder(self, self.inspector)  # recordings and the black box
            self.add_plugin(self.inspector)
            self.add_plugin(self.recorder)
        # the bridge last: its close (the ROS node) comes after the others let go of it
        self.add_plugin(self.ros)
        self.subscribe(self._forget_moved_services)

    def _forget_moved_services(self, event: Event) -> None:
        """After a relaunch, the bridge's clients of services no node of the new plan
        offers are destroyed: they would keep a moved namespace's services on the graph."""
        bridge = self.ros.made
        if isinstance(event, Relaunched) and bridge is not None:
            from .ros.bridge import in_plan

            bridge.drop_clients(in_plan(self.plan))

    def bridge(self) -> Any:
        """The rclpy bridge the launch's ROS actions use (made on first use)."""
        return self.ros.bridge()


def make_supervisor(plan: Plan, log_dir: Path, sigterm_timeout: float = 5.0,
                    sigkill_timeout: float = 5.0,
                    bridge_factory: Callable[[], Any] | None = None,
                    service_timeout: float = 10.0, placement: Placement | None = None,
                    command: list[str] | None = None,
                    arguments: Mapping[str, str] | None = None,
                    session_name: str | None = None, served: bool = True) -> RosSupervisor:
    """A supervisor for `plan` with every ROS plugin; `bridge_factory` shares a bridge the
    caller owns (and closes), else the launch makes its own on first use.

    `placement` (`--machines`, applied to `plan`): the processes placed on other machines
    run there, in shares this launch starts with `command` (FILE or PACKAGE FILE as given)
    and `arguments`, named after `session_name` (run/machines/machines_share.py).
    `served`: a session server serves the launch (False: `--headless`, no inspector)."""
    supervisor = RosSupervisor(plan, log_dir, sigterm_timeout=sigterm_timeout,
                               sigkill_timeout=sigkill_timeout, bridge_factory=bridge_factory,
                               service_timeout=service_timeout, served=served)
    if placement is None:
        return supervisor  # a launch on this machine alone does not load the machines' code
    from .run.machines.machines_share import placement_plugin

    plugin = placement_plugin(supervisor, placement, command or [plan.file],
                              arguments or {}, session_name)
    if plugin is not None:
        supervisor.add_plugin(plugin)
    return supervisor


__all__ = ["BLACK_BOX_ENV", "RosSupervisor", "make_supervisor"]
