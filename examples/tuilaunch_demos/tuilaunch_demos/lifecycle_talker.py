"""A lifecycle node: publishes on `chatter` only while active.

`configure` creates the publisher (refused when the `fail_configure` parameter is true, to
show a failed transition), `activate` starts publishing `<message> <n>` at `rate` Hz,
`deactivate` stops it, `cleanup` drops the publisher.
"""

from rclpy.lifecycle import Node, State, TransitionCallbackReturn
from std_msgs.msg import String

from .common import report_startup, spin


class LifecycleTalker(Node):
    def __init__(self, **node_options) -> None:
        super().__init__("lifecycle_talker", **node_options)
        self.message = self.declare_parameter("message", "hello").value
        self.rate = float(self.declare_parameter("rate", 5.0).value)
        self.fail_configure = bool(self.declare_parameter("fail_configure", False).value)
        self.publisher = None
        self.timer = None
        self.sent = 0
        report_startup(self, {})

    def on_configure(self, state: State) -> TransitionCallbackReturn:
        if self.fail_configure:
            self.get_logger().error("configure refused: fail_configure is true")
            return TransitionCallbackReturn.FAILURE
        self.publisher = self.create_lifecycle_publisher(String, "chatter", 10)
        self.get_logger().info("configured")
        return TransitionCallbackReturn.SUCCESS

    def on_activate(self, state: State) -> TransitionCallbackReturn:
        self.timer = self.create_timer(1.0 / self.rate, self.tick)
        self.get_logger().info("activated")
        return super().on_activate(state)

    def on_deactivate(self, state: State) -> TransitionCallbackReturn:
        if self.timer is not None:
            self.destroy_timer(self.timer)
            self.timer = None
        self.get_logger().info("deactivated")
        return super().on_deactivate(state)

    def on_cleanup(self, state: State) -> TransitionCallbackReturn:
        if self.publisher is not None:
            self.destroy_publisher(self.publisher)
            self.publisher = None
        self.get_logger().info("cleaned up")
        return TransitionCallbackReturn.SUCCESS

    def on_shutdown(self, state: State) -> TransitionCallbackReturn:
        self.get_logger().info("shut down")
        return TransitionCallbackReturn.SUCCESS

    def tick(self) -> None:
        self.sent += 1
        text = f"{self.message} {self.sent}"
        if self.publisher is not None:
            self.publisher.publish(String(data=text))
        self.get_logger().info(f'Publishing: "{text}"')


def main() -> None:
    spin(LifecycleTalker)
