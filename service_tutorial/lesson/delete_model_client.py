"""
Delete a model through /mujoco/delete_model.

The counterpart of the lesson's `rosservice call /gazebo/delete_model "model_name: 'r2d2'"`
for machines without the ros2 command; with it, the same call is
`ros2 service call /mujoco/delete_model srv_interfaces/srv/DeleteModel "{model_name: 'r2d2'}"`.
"""

import sys

from rclpy.node import Node

from service_tutorial.lesson.client_arguments import parse_client_arguments
from service_tutorial.lesson.model_services import delete_model, response_text
from service_tutorial.node_main import program_arguments, run_node


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    return parse_client_arguments(
        argv, 'delete_model_client', 'Delete a model through /mujoco/delete_model.',
        lambda parser: parser.add_argument('model_name', nargs='?', default='r2d2',
                                           help='model to delete (default: %(default)s)'))


def main(args=None):
    """Delete one model, print the response, exit with status 0 if the world deleted it."""
    options = parse_arguments(program_arguments(args))

    def delete(node):
        response = delete_model(node, options.model_name, timeout=options.timeout)
        print(response_text(response))
        return 0 if response.success else 1
    return run_node(lambda: Node('delete_model_client'), delete, args=args,
                    program='delete_model_client', errors=(TimeoutError,))


if __name__ == '__main__':
    sys.exit(main())
