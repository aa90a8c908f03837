"""A node with typed, described parameters; refuses invalid values with a reason."""

from rcl_interfaces.msg import (
    FloatingPointRange,
    IntegerRange,
    ParameterDescriptor,
    SetParametersResult,
)
from rclpy.node import Node

from .common import report_startup, spin


class Configurable(Node):
    def __init__(self) -> None:
        super().__init__("configurable")
        self.declare_parameter("speed", 1.0, ParameterDescriptor(
            description="cruise speed [m/s]",
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=5.0)]))
        self.declare_parameter("mode", "idle", ParameterDescriptor(
            description="one of idle, patrol, dock"))
        self.declare_parameter("enabled", True, ParameterDescriptor(description="motors on"))
        self.declare_parameter("gains", [1.0, 0.5, 0.0], ParameterDescriptor(
            description="PID gains"))
        self.declare_parameter("robot_id", 7, ParameterDescriptor(
            description="fixed at start", read_only=True,
            integer_range=[IntegerRange(from_value=0, to_value=100, step=1)]))
        self.declare_parameter("label", "demo", ParameterDescriptor(description="display name"))
        self.add_on_set_parameters_callback(self.check)
        report_startup(self, {})

    def check(self, params: list) -> SetParametersResult:
        for param in params:
            if param.name == "mode" and param.value not in ("idle", "patrol", "dock"):
                return SetParametersResult(
                    successful=False, reason=f"mode must be idle, patrol or dock, not {param.value!r}")
        for param in params:
            self.get_logger().info(f"parameter {param.name} set to {param.value!r}")
        return SetParametersResult(successful=True)


def main() -> None:
    spin(Configurable)
