"""One rclpy node for the inspector tests: publishes and/or subscribes with chosen QoS,
declares parameters, offers the logger service, burns CPU. Prints 'ready' once the node
exists. Started by a launch file too: launch's `--ros-args ...` go to rclpy."""

import argparse
import sys
import threading
import time

import rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.utilities import remove_ros_args
from std_msgs.msg import Int32MultiArray, String

parser = argparse.ArgumentParser()
parser.add_argument("name")
parser.add_argument("--namespace", default="/")
parser.add_argument("--pub")
parser.add_argument("--sub")
parser.add_argument("--rate", type=float, default=10.0)
parser.add_argument("--best-effort", action="store_true")
parser.add_argument("--transient-local", action="store_true")
parser.add_argument("--depth", type=int, default=10, help="the history a publisher keeps")
parser.add_argument("--burst", type=int, default=0,
                    help="publish N messages at once before the timer starts")
parser.add_argument("--array", type=int, default=0, help="publish Int32MultiArray of N")
parser.add_argument("--params", action="store_true")
parser.add_argument("--logger-service", action="store_true")
parser.add_argument("--debug-ticks", action="store_true")
parser.add_argument("--burn", type=float, default=0.0,
                    help="keep this share of one core busy (0.3: 30 %%)")
args = parser.parse_args(remove_ros_args(sys.argv)[1:])

rclpy.init()
node = rclpy.create_node(args.name, namespace=args.namespace,
                         enable_logger_service=args.logger_service)
qos = QoSProfile(depth=args.depth)
if args.best_effort:
    qos.reliability = ReliabilityPolicy.BEST_EFFORT
if args.transient_local:
    qos.durability = DurabilityPolicy.TRANSIENT_LOCAL
if args.params:
    node.declare_parameters("", [("rate", 10.0), ("label", "lidar"), ("enabled", True),
                                 ("gains.p", 1.5), ("gains.i", 0.25),
                                 ("limits.speed.max", 2), ("frames", ["base", "laser"])])
count = 0
if args.pub:
    kind = Int32MultiArray if args.array else String
    publisher = node.create_publisher(kind, args.pub, qos)

    def publish() -> None:
        global count
        count += 1
        if args.array:
            publisher.publish(Int32MultiArray(data=list(range(args.array))))
        else:
            publisher.publish(String(data=f"hello {count}"))

    for _ in range(args.burst):  # a transient-local history a late subscriber is handed
        publish()
    node.create_timer(1.0 / args.rate, publish)
if args.sub:
    node.create_subscription(String, args.sub, lambda msg: None, qos)
if args.debug_ticks:
    node.create_timer(0.1, lambda: node.get_logger().debug("debug tick"))
if args.burn:
    def burn() -> None:
        # busy for a share of each 100 ms: a steady load that leaves the machine usable
        while True:
            end = time.monotonic() + 0.1 * args.burn
            while time.monotonic() < end:
                pass
            time.sleep(0.1 * (1 - args.burn))

    threading.Thread(target=burn, daemon=True).start()
node.get_logger().info("up")  # its logger name says which node it is
print("ready", flush=True)
try:
    rclpy.spin(node)
except Exception:
    pass
