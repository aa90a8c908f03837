"""A component container in Python, speaking rclcpp_components' protocol.

Serves `~/_container/load_node`, `~/_container/unload_node` and `~/_container/list_nodes`
(composition_interfaces) and runs the loaded nodes in its own executor. A plugin
`package::Class` is the node class `Class` of the Python module `package.components`; the
class takes rclpy Node keyword arguments. Needs composition_interfaces to be importable.
"""

import importlib
import sys

import rclpy
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter


class ComponentManager(Node):
    def __init__(self, executor, interfaces) -> None:
        super().__init__("ComponentManager")
        self.executor_ = executor
        self.interfaces = interfaces
        self.loaded: dict[int, Node] = {}
        self.next_id = 1
        self.create_service(interfaces.LoadNode, "~/_container/load_node", self.load)
        self.create_service(interfaces.UnloadNode, "~/_container/unload_node", self.unload)
        self.create_service(interfaces.ListNodes, "~/_container/list_nodes", self.list)

    def load(self, request, response):
        try:
            node_class = self.find_class(request.package_name, request.plugin_name)
            options = self.node_options(request)
        except LookupError as exc:
            response.success, response.error_message = False, str(exc)
            self.get_logger().error(str(exc))
            return response
        try:
            node = node_class(**options)
        except Exception as exc:
            response.success = False
            response.error_message = f"Component constructor threw an exception: {exc}"
            self.get_logger().error(response.error_message)
            return response
        unique_id = self.next_id
        self.next_id += 1
        self.loaded[unique_id] = node
        self.executor_.add_node(node)
        response.success = True
        response.full_node_name = node.get_fully_qualified_name()
        response.unique_id = unique_id
        self.get_logger().info(f"Load Library: {request.package_name} {request.plugin_name}")
        self.get_logger().info(f"Found class: {request.plugin_name}")
        return response

    def find_class(self, package: str, plugin: str):
        try:
            module = importlib.import_module(f"{package}.components")
        except ImportError:
            raise LookupError("Could not find requested resource in ament index") from None
        node_class = getattr(module, plugin.split("::")[-1], None)
        if not isinstance(node_class, type) or not issubclass(node_class, Node):
            raise LookupError("Failed to find class with the requested plugin name.")
        return node_class

    def node_options(self, request) -> dict:
        rules = []
        if request.node_name:
            rules += ["-r", f"__node:={request.node_name}"]
        if request.node_namespace:
            rules += ["-r", f"__ns:={request.node_namespace}"]
        for rule in request.remap_rules:
            rules += ["-r", rule]
        for arg in request.extra_arguments:
            if arg.name == "use_intra_process_comms" and arg.value.type != 1:
                raise LookupError(
                    "Extra component argument 'use_intra_process_comms' must be a boolean")
        overrides = [Parameter.from_parameter_msg(p) for p in request.parameters]
        return {"cli_args": ["--ros-args", *rules] if rules else None,
                "use_global_arguments": False, "parameter_overrides": overrides}

    def unload(self, request, response):
        node = self.loaded.pop(request.unique_id, None)
        if node is None:
            response.success = False
            response.error_message = "No node found with unique_id: " + str(request.unique_id)
            return response
        self.executor_.remove_node(node)
        node.destroy_node()
        response.success = True
        return response

    def list(self, request, response):
        response.unique_ids = list(self.loaded)
        response.full_node_names = [n.get_fully_qualified_name() for n in self.loaded.values()]
        return response


def main() -> None:
    try:
        from composition_interfaces import srv as interfaces
    except ImportError:
        print("component_container: composition_interfaces is not importable", file=sys.stderr)
        sys.exit(1)
    rclpy.init(args=sys.argv)
    executor = MultiThreadedExecutor()
    manager = ComponentManager(executor, interfaces)
    executor.add_node(manager)
    try:
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        executor.shutdown()
        rclpy.try_shutdown()
