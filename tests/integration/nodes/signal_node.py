"""An rclpy node publishing a known signal for the plot tests, as geometry_msgs/Point:
x = AMPLITUDE * sin(2 pi FREQUENCY k / RATE), but SPIKE at one sample every SPIKE_EVERY
seconds; y = x / 2; z = k, the sample's number, so a reader can recompute what x and y were
(`expected(k)`). Published from a plain thread at RATE per second (catching up in bursts
when the machine is slow), no executor: a 1 kHz topic costs little. Prints 'ready'."""

import argparse
import math
import sys
import threading
import time

AMPLITUDE, FREQUENCY, SPIKE = 2.0, 0.5, 10.0


def expected(k: int, rate: float, spike_every: float) -> tuple[float, float]:
    """(x, y) of sample k."""
    every = max(1, round(spike_every * rate))
    x = SPIKE if spike_every > 0 and k % every == every // 2 else \
        AMPLITUDE * math.sin(2 * math.pi * FREQUENCY * k / rate)
    return x, x / 2


def main() -> None:
    import rclpy
    from geometry_msgs.msg import Point
    from rclpy.utilities import remove_ros_args

    parser = argparse.ArgumentParser()
    parser.add_argument("name")
    parser.add_argument("--topic", default="wave")
    parser.add_argument("--rate", type=float, default=50.0)
    parser.add_argument("--spike-every", type=float, default=4.0)
    args = parser.parse_args(remove_ros_args(sys.argv)[1:])
    rclpy.init()
    node = rclpy.create_node(args.name)
    publisher = node.create_publisher(Point, args.topic, 10)
    print("ready", flush=True)

    def publish() -> None:
        period = 1.0 / args.rate
        start = time.monotonic()
        k = 0
        while rclpy.ok():
            x, y = expected(k, args.rate, args.spike_every)
            publisher.publish(Point(x=x, y=y, z=float(k)))
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
