"""
Reset the simulation through /mujoco/reset_simulation: time 0, every model at its spawn pose.

The counterpart of `rosservice call /gazebo/reset_simulation` for machines without the ros2
command; with it: `ros2 service call /mujoco/reset_simulation std_srvs/srv/Empty`.
"""

import argparse
import sys

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.utilities import remove_ros_args

from service_tutorial.model_services import DEFAULT_TIMEOUT, reset_simulation


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    parser = argparse.ArgumentParser(
        prog='reset_simulation_client',
        description='Reset the simulation through /mujoco/reset_simulation.')
    parser.add_argument('--timeout', type=float, default=DEFAULT_TIMEOUT,
                        help='seconds to wait for the service and its answer '
                             '(default: %(default)s)')
    return parser.parse_args(argv)


def main(args=None):
    """Reset the simulation; exit with status 0 once the world has done it."""
    options = parse_arguments(remove_ros_args(sys.argv if args is None else args)[1:])
    rclpy.init(args=args)
    node = None
    status = 1
    try:
        node = Node('reset_simulation_client')
        reset_simulation(node, timeout=options.timeout)
        node.get_logger().info('simulation reset')
        status = 0
    except TimeoutError as error:
        print(f'reset_simulation_client: {error}', file=sys.stderr)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


if __name__ == '__main__':
    sys.exit(main())
