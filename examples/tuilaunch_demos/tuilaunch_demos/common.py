"""What every demo node shares: a clean Ctrl+C and a startup report of what it received."""

import json
import sys

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node


def report_startup(node: Node, topics: dict[str, str]) -> None:
    """One line a launcher's tests can read: name, namespace, parameters, resolved topics."""
    params = {name: p.value for name, p in sorted(node._parameters.items())
              if name != "use_sim_time" or p.value}
    info = {"node": node.get_fully_qualified_name(), "namespace": node.get_namespace(),
            "parameters": params, "topics": topics}
    print("STARTUP " + json.dumps(info, default=list), flush=True)


def spin(make_node) -> None:
    rclpy.init(args=sys.argv)
    node = make_node()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
