"""std_srvs servers: `reset` (Trigger) counts resets; `enable` (SetBool) toggles a flag."""

from rclpy.node import Node
from std_srvs.srv import SetBool, Trigger

from .common import report_startup, spin


class ServiceServer(Node):
    def __init__(self) -> None:
        super().__init__("service_server")
        self.resets = 0
        self.enabled = False
        self.create_service(Trigger, "reset", self.on_reset)
        self.create_service(SetBool, "enable", self.on_enable)
        report_startup(self, {})

    def on_reset(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self.resets += 1
        response.success = True
        response.message = f"reset #{self.resets}"
        self.get_logger().info(f"reset called ({self.resets} so far)")
        return response

    def on_enable(self, request: SetBool.Request, response: SetBool.Response) -> SetBool.Response:
        self.enabled = request.data
        response.success = True
        response.message = "enabled" if request.data else "disabled"
        self.get_logger().info(f"enable called with data={request.data}")
        return response


def main() -> None:
    spin(ServiceServer)
