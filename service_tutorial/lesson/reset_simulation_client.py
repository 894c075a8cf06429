"""
Reset the simulation through /mujoco/reset_simulation: time 0, every model at its spawn pose.

The counterpart of `rosservice call /gazebo/reset_simulation` for machines without the ros2
command; with it: `ros2 service call /mujoco/reset_simulation std_srvs/srv/Empty`.
"""

import sys

from rclpy.node import Node

from service_tutorial.lesson.client_arguments import parse_client_arguments
from service_tutorial.lesson.model_services import reset_simulation
from service_tutorial.node_main import program_arguments, run_node


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    return parse_client_arguments(argv, 'reset_simulation_client',
                                  'Reset the simulation through /mujoco/reset_simulation.')


def main(args=None):
    """Reset the simulation; exit with status 0 once the world has done it."""
    options = parse_arguments(program_arguments(args))

    def reset(node):
        reset_simulation(node, timeout=options.timeout)
        node.get_logger().info('simulation reset')
        return 0
    return run_node(lambda: Node('reset_simulation_client'), reset, args=args,
                    program='reset_simulation_client', errors=(TimeoutError,))


if __name__ == '__main__':
    sys.exit(main())
