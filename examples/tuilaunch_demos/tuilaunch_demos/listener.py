"""Logs every String heard on `chatter`."""

from rclpy.node import Node
from std_msgs.msg import String

from .common import report_startup, spin


class Listener(Node):
    def __init__(self, **node_options) -> None:
        super().__init__("listener", **node_options)
        self.subscription = self.create_subscription(String, "chatter", self.heard, 10)
        report_startup(self, {"chatter": self.subscription.topic_name})

    def heard(self, msg: String) -> None:
        self.get_logger().info(f'I heard: "{msg.data}"')


def main() -> None:
    spin(Listener)
