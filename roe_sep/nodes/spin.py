"""The Jazzy ``main()`` idiom shared by every node: init, construct, spin, clean shutdown, exit code."""

import sys

import rclpy
from rclpy.executors import ExternalShutdownException

from .params import ParameterError


def run(node_factory, args=None) -> int:
    """Spin the node built by ``node_factory()``; a :class:`ParameterError` at start-up exits with code 2."""
    rclpy.init(args=args)
    node = None
    try:
        node = node_factory()
        rclpy.spin(node)
    except ParameterError as exc:
        print(f"[ERROR] {exc}", file=sys.stderr)
        return 2
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
