"""Loading composable nodes through `<container>/_container/load_node`.

One `ComponentLoader` per supervisor. A container's own components are loaded, in order, each
time its process starts (so a restarted or respawned container gets them back, which
launch_ros does not do); components of a `LoadComposableNodes` action are loaded when the
action runs and, when the container is one of this launch's processes, again whenever it
restarts. Every component gets a `component` event with its result: the unique id the
container gave it, the container's error, or why no request could be sent.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Mapping
from typing import Any

from ..plan.model import ActionKind, ActionPlan, ProcessPlan
from ..run.events import ComponentReport
from ..run.plugins import ActionRunner, Plugin
from ..run.supervisor.supervisor import Supervisor
from .actions import RosActions

LOAD_TIMEOUT = 30.0  # a component's constructor may take a while (maps, models)
# A container that crashed stays on the graph until its DDS lease ends: a request sent then
# reaches the dead server only. Unanswered attempts are retried (after checking that the
# node did not load meanwhile) until LOAD_TIMEOUT.
ATTEMPT_TIMEOUT = 5.0
ALIVE = ("pending", "running", "respawning")
MISSING_INTERFACES = ("composition_interfaces is not installed: source /opt/ros/jazzy (or a "
                      "workspace that has it) to load components")


def load_node_class() -> Any:
    """`composition_interfaces.srv.LoadNode`, or None when the package is not importable."""
    try:
        from composition_interfaces.srv import LoadNode
    except ImportError:
        return None
    return LoadNode


def build_request(load_node: Any, component: dict[str, Any]) -> Any:
    """The LoadNode request a plan's component stands for."""
    from rcl_interfaces.msg import Parameter

    from .bridge import parameter_value

    fields = component["request"]
    request = load_node.Request()
    request.package_name = fields["package_name"]
    request.plugin_name = fields["plugin_name"]
    request.node_name = fields["node_name"]
    request.node_namespace = fields["node_namespace"]
    request.remap_rules = list(fields["remap_rules"])
    request.parameters = [Parameter(name=k, value=parameter_value(v))
                          for k, v in component["parameters"].items()]
    request.extra_arguments = [Parameter(name=k, value=parameter_value(v))
                               for k, v in component["extra_arguments"].items()]
    return request


class ComponentLoader(Plugin):
    """Results of every component of the launch, by component id.

    A supervisor plugin: it performs the plan's `load_components` actions and loads a
    container's components whenever its process starts."""

    def __init__(self, supervisor: Supervisor, ros: RosActions) -> None:
        self.supervisor = supervisor
        self.ros = ros
        self.results: dict[str, dict[str, Any]] = {}
        # components of LoadComposableNodes actions that already ran, by container name
        self._loaded_by_actions: dict[str, list[tuple[str, dict[str, Any]]]] = {}
        self._locks: dict[str, asyncio.Lock] = {}

    def actions(self) -> Mapping[str, ActionRunner]:
        return {ActionKind.LOAD_COMPONENTS: self.run_action}

    def process_started(self, proc: ProcessPlan) -> Awaitable[Any] | None:
        # any node may be a container (nav2 starts one with Node): it loads what targets it
        return self.container_started(proc)

    def container_started(self, proc: ProcessPlan) -> Awaitable[bool] | None:
        """Loading of the container's own components, then of those actions loaded before.

        What to load is decided now, as the process starts: an action that runs later (an
        OnProcessStart handler) loads its own components, and must not be loaded twice."""
        owned = [(proc.id, c) for c in proc.components]
        extra = list(self._loaded_by_actions.get(proc.full_name or "", []))
        if not owned and not extra:
            return None
        return self._load_all(proc.full_name or "", [*owned, *extra], proc.id)

    async def run_action(self, action: ActionPlan) -> bool:
        container = str(action.target)
        components: list[dict[str, Any]] = list(action.data or [])
        pairs = [(action.id, c) for c in components]
        self._loaded_by_actions.setdefault(container, []).extend(pairs)
        local = self._container_process(container)
        if local is not None and self.supervisor.states.get(local.id) != "running":
            for _, component in pairs:
                self._result(action.id, component, "waiting",
                             f"waits for its container {container} to start")
            return True  # container_started loads them when it starts
        return await self._load_all(container, pairs, local.id if local else None)

    def _container_process(self, name: str) -> ProcessPlan | None:
        for proc in self.supervisor.plan.processes:
            if proc.enabled and proc.full_name == name:
                return proc
        return None

    async def _load_all(self, container: str, pairs: list[tuple[str, dict[str, Any]]],
                        proc_id: str | None) -> bool:
        """Sequentially, as launch_ros loads them; one failure does not stop the others."""
        lock = self._locks.setdefault(container, asyncio.Lock())
        ok = True
        async with lock:
            for owner, component in pairs:
                if not component.get("enabled", True):
                    self._result(owner, component, "skipped", "its condition is false")
                    continue
                ok = await self._load(container, owner, component, proc_id) and ok
        return ok

    async def _load(self, container: str, owner: str, component: dict[str, Any],
                    proc_id: str | None) -> bool:
        # the file and line that declared the component, for every failure
        what = f"{component['plugin']} into {container}" + (
            f" ({component['origin']})" if component.get("origin") else "")
        load_node = load_node_class()
        if load_node is None:
            self._result(owner, component, "failed", f"cannot load {what}: "
                         f"{MISSING_INTERFACES}", "ERROR")
            return False
        if component.get("error"):
            self._result(owner, component, "failed", f"cannot load {what}: "
                         f"{component['error']}", "ERROR")
            return False
        try:
            request = build_request(load_node, component)
        except Exception as exc:  # a parameter value ROS cannot carry
            self._result(owner, component, "failed", f"cannot load {what}: {exc}", "ERROR")
            return False
        try:
            bridge = self.ros.bridge()
        except Exception as exc:
            self._result(owner, component, "failed", f"cannot load {what}: no ROS "
                         f"connection ({exc})", "ERROR")
            return False
        service = f"{container}/_container/load_node"
        self._result(owner, component, "loading", f"waiting for {service}")
        if not await self._wait_for_service(bridge, service, proc_id):
            self._result(owner, component, "cancelled",
                         f"not loaded: {container} stopped before its load service came up",
                         "WARN")
            return False
        try:
            response = await self._call(bridge, container, request, component, proc_id)
        except Exception as exc:
            self._result(owner, component, "failed", f"loading {what} failed: {exc}",
                         "ERROR")
            return False
        if not response.success:
            self._result(owner, component, "failed",
                         f"{container} could not load {what}: {response.error_message}",
                         "ERROR", error=response.error_message)
            return False
        self._result(owner, component, "loaded",
                     f"loaded {response.full_node_name} ({component['plugin']}) into "
                     f"{container}, unique id {response.unique_id}",
                     unique_id=int(response.unique_id), node=response.full_node_name)
        return True

    async def _call(self, bridge: Any, container: str, request: Any,
                    component: dict[str, Any], proc_id: str | None) -> Any:
        from .bridge import RosError

        request_kind = type(request).__qualname__  # only for the error text
        loop = asyncio.get_running_loop()
        deadline = loop.time() + LOAD_TIMEOUT
        service = f"{container}/_container/load_node"
        while True:
            try:
                return await bridge.call_typed(service, load_node_class(), request,
                                               ATTEMPT_TIMEOUT)
            except RosError:
                alive = proc_id is None or self.supervisor.states.get(proc_id) == "running"
                if loop.time() > deadline or not alive or self.supervisor.shutting_down:
                    raise RosError(f"{container} did not answer the {request_kind} request "
                                   f"within {LOAD_TIMEOUT:g} s") from None
                found = await self._listed(bridge, container, component.get("full_name"))
                if found is not None:
                    return found

    async def _listed(self, bridge: Any, container: str, full_name: str | None) -> Any:
        """A response for a node the container lists already (an answer that got lost)."""
        if not full_name:
            return None
        try:
            from composition_interfaces.srv import ListNodes, LoadNode

            listed = await bridge.call_typed(f"{container}/_container/list_nodes", ListNodes,
                                             ListNodes.Request(), ATTEMPT_TIMEOUT)
        except Exception:  # no answer either: try loading again
            return None
        for name, unique_id in zip(listed.full_node_names, listed.unique_ids, strict=False):
            if name == full_name:
                return LoadNode.Response(success=True, full_node_name=name,
                                         unique_id=int(unique_id))
        return None

    async def _wait_for_service(self, bridge: Any, service: str, proc_id: str | None) -> bool:
        while not self.supervisor.shutting_down:
            if proc_id is not None and self.supervisor.states.get(proc_id) not in ALIVE:
                return False
            try:
                await bridge.wait_for_service(service, 1.0)
                return True
            except Exception:  # not up yet
                continue
        return False

    def _result(self, owner: str, component: dict[str, Any], state: str, text: str,
                level: str = "INFO", **extra: Any) -> None:
        data = {"component": component["id"], "state": state, "text": text,
                "container": component.get("container"), **extra}
        self.results[component["id"]] = data
        if state == "failed":  # the exit status says so, listed in a container or not
            self.supervisor.failed_parts.add(component["id"])
        elif state == "loaded":  # loaded again after its container restarted
            self.supervisor.failed_parts.discard(component["id"])
        self.supervisor.emit(ComponentReport(owner, reason=text, level=level, data=data))


__all__ = ["ComponentLoader", "build_request", "load_node_class"]
