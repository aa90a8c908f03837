"""Publishes `<message> <n>` on `chatter` at `rate` Hz; stops after `count` if positive."""

import sys

from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node
from std_msgs.msg import String

from .common import report_startup, spin


class Talker(Node):
    def __init__(self, **node_options) -> None:
        super().__init__("talker", **node_options)
        self.message = self.declare_parameter("message", "hello").value
        # dynamic typing: `rate:=5` arrives as an integer from a launch argument
        rate = float(self.declare_parameter(
            "rate", 2.0, ParameterDescriptor(dynamic_typing=True)).value)
        self.count = int(self.declare_parameter("count", 0).value)
        self.publisher = self.create_publisher(String, "chatter", 10)
        self.sent = 0
        report_startup(self, {"chatter": self.publisher.topic_name})
        self.create_timer(1.0 / rate, self.tick)

    def tick(self) -> None:
        self.sent += 1
        text = f"{self.message} {self.sent}"
        self.publisher.publish(String(data=text))
        self.get_logger().info(f'Publishing: "{text}"')
        if self.count and self.sent >= self.count:
            self.get_logger().info("done")
            sys.exit(0)


def main() -> None:
    spin(Talker)
