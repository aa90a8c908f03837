"""An rclpy node for the recording tests and bench: N small topics (`/flood/small_i`,
std_msgs/String "i k") at RATE, and one image topic (`/flood/image`, sensor_msgs/Image
WIDTHxHEIGHT rgb8, its number k in header.stamp.sec and its first pixel byte k % 256) at
IMAGE_RATE; published from a plain thread, no executor. Prints 'ready'."""

import argparse
import sys
import threading
import time


def main() -> None:
    import rclpy
    from rclpy.utilities import remove_ros_args
    from sensor_msgs.msg import Image
    from std_msgs.msg import String

    parser = argparse.ArgumentParser()
    parser.add_argument("name")
    parser.add_argument("--topics", type=int, default=0)
    parser.add_argument("--rate", type=float, default=100.0)
    parser.add_argument("--image-rate", type=float, default=0.0)
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--height", type=int, default=480)
    args = parser.parse_args(remove_ros_args(sys.argv)[1:])
    rclpy.init()
    node = rclpy.create_node(args.name)
    small = [node.create_publisher(String, f"/flood/small_{i}", 10) for i in range(args.topics)]
    image_pub = node.create_publisher(Image, "/flood/image", 10) if args.image_rate else None
    print("ready", flush=True)

    def every(rate: float, publish) -> None:
        period = 1.0 / rate
        start = time.monotonic()
        k = 0
        while rclpy.ok():
            publish(k)
            k += 1
            delay = start + k * period - time.monotonic()
            if delay > 0:
                time.sleep(delay)

    def publish_small(k: int) -> None:
        for i, publisher in enumerate(small):
            publisher.publish(String(data=f"{i} {k}"))

    pixels = bytearray(args.width * args.height * 3)

    def publish_image(k: int) -> None:
        pixels[0] = k % 256
        image = Image(height=args.height, width=args.width, encoding="rgb8",
                      step=args.width * 3)
        image.header.stamp.sec = k
        image.data = bytes(pixels)
        image_pub.publish(image)

    if small:
        threading.Thread(target=every, args=(args.rate, publish_small), daemon=True).start()
    if image_pub is not None:
        threading.Thread(target=every, args=(args.image_rate, publish_image),
                         daemon=True).start()
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, Exception):
        pass


if __name__ == "__main__":
    main()
