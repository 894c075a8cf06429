"""
Ask the world for a picture through /mujoco/save_snapshot and print where it was written.

The world renders its camera's view (camera_position, camera_look_at in config/world.yaml)
and writes the PNG into its snapshot_directory parameter; the request carries no path. With the
ros2 command: `ros2 service call /mujoco/save_snapshot std_srvs/srv/Trigger`.
"""

import sys

from rclpy.node import Node
from service_tutorial.lesson.client_arguments import parse_client_arguments
from service_tutorial.lesson.model_services import call, DEFAULT_TIMEOUT
from service_tutorial.node_main import program_arguments, run_node
from std_srvs.srv import Trigger

# Relative, like the model services: /mujoco/save_snapshot from the root namespace.
SAVE_SNAPSHOT_SERVICE = 'mujoco/save_snapshot'


class SnapshotClient(Node):
    """Calls the world's save_snapshot service."""

    def __init__(self):
        super().__init__('save_snapshot_client')
        self.snapshot_cli = self.create_client(Trigger, SAVE_SNAPSHOT_SERVICE)

    def save_snapshot(self, *, timeout=DEFAULT_TIMEOUT):
        """Have the world write a snapshot; return the path, or raise with its reason."""
        response = call(self, self.snapshot_cli, Trigger.Request(), timeout=timeout)
        if not response.success:
            raise RuntimeError(response.message)
        return response.message


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    return parse_client_arguments(
        argv, 'save_snapshot',
        'Have the MuJoCo world write a PNG of its camera view; print its path.')


def main(args=None):
    """Save a snapshot and print its path; exit with status 0 once it is written."""
    options = parse_arguments(program_arguments(args))

    def save(node):
        print(node.save_snapshot(timeout=options.timeout))
        return 0
    return run_node(SnapshotClient, save, args=args, program='save_snapshot',
                    errors=(TimeoutError, RuntimeError))


if __name__ == '__main__':
    sys.exit(main())
