"""An rclpy node publishing known joint states for the plot tests, as sensor_msgs/JointState
(a header.stamp, a sequence of positions): sample k is stamped ORIGIN + k / RATE seconds
(1970-01-12: far from the clock, so a plot by stamp and by arrival differ), its positions
are `positions(k)`: a sine of amplitude 1, a sine of amplitude 1e5 (magnitudes that one
axis cannot show together), and k itself, so a reader recomputes what was published.
Published from a plain thread at RATE per second, no executor. Prints 'ready'."""

import argparse
import math
import sys
import threading
import time

ORIGIN = 1_000_000
"""The first stamp, in seconds since the epoch."""
BIG = 1e5


def positions(k: int, rate: float) -> list[float]:
    phase = 2 * math.pi * 0.5 * k / rate
    return [math.sin(phase), BIG * math.cos(phase), float(k)]


def stamp(k: int, rate: float) -> tuple[int, int]:
    """(sec, nanosec) of sample k: whole nanoseconds, so the CSV's seconds are exact."""
    nanoseconds = ORIGIN * 10**9 + k * round(10**9 / rate)
    return nanoseconds // 10**9, nanoseconds % 10**9


def main() -> None:
    import rclpy
    from rclpy.utilities import remove_ros_args
    from sensor_msgs.msg import JointState

    parser = argparse.ArgumentParser()
    parser.add_argument("name")
    parser.add_argument("--topic", default="joints")
    parser.add_argument("--rate", type=float, default=50.0)
    args = parser.parse_args(remove_ros_args(sys.argv)[1:])
    rclpy.init()
    node = rclpy.create_node(args.name)
    publisher = node.create_publisher(JointState, args.topic, 10)
    print("ready", flush=True)

    def publish() -> None:
        period = 1.0 / args.rate
        start = time.monotonic()
        k = 0
        while rclpy.ok():
            message = JointState(name=["pan", "lift", "count"],
                                 position=positions(k, args.rate))
            message.header.stamp.sec, message.header.stamp.nanosec = stamp(k, args.rate)
            publisher.publish(message)
            k += 1
            delay = start + k * period - time.monotonic()
            if delay > 0:
                time.sleep(delay)

    threading.Thread(target=publish, daemon=True).start()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, Exception):
        pass


if __name__ == "__main__":
    main()
