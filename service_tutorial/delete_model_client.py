"""
Delete a model through /mujoco/delete_model.

The counterpart of the lesson's `rosservice call /gazebo/delete_model "model_name: 'r2d2'"`
for machines without the ros2 command; with it, the same call is
`ros2 service call /mujoco/delete_model srv_interfaces/srv/DeleteModel "{model_name: 'r2d2'}"`.
"""

import argparse
import sys

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.utilities import remove_ros_args

from service_tutorial.model_services import DEFAULT_TIMEOUT, delete_model, response_text


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    parser = argparse.ArgumentParser(
        prog='delete_model_client', description='Delete a model through /mujoco/delete_model.')
    parser.add_argument('model_name', nargs='?', default='r2d2',
                        help='model to delete (default: %(default)s)')
    parser.add_argument('--timeout', type=float, default=DEFAULT_TIMEOUT,
                        help='seconds to wait for the service and its answer '
                             '(default: %(default)s)')
    return parser.parse_args(argv)


def main(args=None):
    """Delete one model, print the response, exit with status 0 if the world deleted it."""
    options = parse_arguments(remove_ros_args(sys.argv if args is None else args)[1:])
    rclpy.init(args=args)
    node = None
    status = 1
    try:
        node = Node('delete_model_client')
        response = delete_model(node, options.model_name, timeout=options.timeout)
        print(response_text(response))
        status = 0 if response.success else 1
    except TimeoutError as error:
        print(f'delete_model_client: {error}', file=sys.stderr)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


if __name__ == '__main__':
    sys.exit(main())
