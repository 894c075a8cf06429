"""
Spawn R2-D2 next to tinybot through /mujoco/spawn_urdf_model, as the lesson does.

The ROS 2 counterpart of the lesson's spawn_model_client.py: it reads models/r2d2.urdf from
the package share and asks the world to put it at (-2, 1, 1), turned -90 degrees about z, in the
world frame. Options choose another model, name, pose, namespace or reference frame.
"""

import argparse
import os
import sys

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.utilities import remove_ros_args

from service_tutorial.conversions import make_pose
from service_tutorial.model_services import DEFAULT_TIMEOUT, model_path, response_text
from service_tutorial.model_services import spawn_model

# The lesson's pose: z rotation of -pi/2 as a quaternion (x, y, z, w).
LESSON_POSITION = (-2.0, 1.0, 1.0)
LESSON_QUATERNION = (0.0, 0.0, -0.707, 0.707)


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    parser = argparse.ArgumentParser(
        prog='spawn_model_client',
        description='Spawn a URDF model through /mujoco/spawn_urdf_model '
                    '(by default R2-D2 where the lesson puts it).')
    parser.add_argument('--file', default='r2d2.urdf',
                        help="URDF file: a path, or a file name in this package's models/ "
                             'folder (default: %(default)s)')
    parser.add_argument('--name', default='r2d2', help='model name (default: %(default)s)')
    parser.add_argument('-x', type=float, default=LESSON_POSITION[0], help='x in m (default: -2)')
    parser.add_argument('-y', type=float, default=LESSON_POSITION[1], help='y in m (default: 1)')
    parser.add_argument('-z', type=float, default=LESSON_POSITION[2], help='z in m (default: 1)')
    orientation = parser.add_mutually_exclusive_group()
    orientation.add_argument('--yaw', type=float, help='heading in rad (default: -pi/2)')
    orientation.add_argument('--quaternion', type=float, nargs=4, metavar=('QX', 'QY', 'QZ', 'QW'),
                             help='orientation as a quaternion (default: 0 0 -0.707 0.707)')
    parser.add_argument('--namespace', default='',
                        help="namespace of the model's topics (default: none)")
    parser.add_argument('--reference-frame', default='world',
                        help='frame the pose is given in (default: %(default)s)')
    parser.add_argument('--timeout', type=float, default=DEFAULT_TIMEOUT,
                        help='seconds to wait for the service and its answer '
                             '(default: %(default)s)')
    options = parser.parse_args(argv)
    if options.yaw is None and options.quaternion is None:
        options.quaternion = LESSON_QUATERNION
    if not os.path.isfile(options.file):
        options.file = model_path(options.file)
    return options


def main(args=None):
    """Spawn one model, print the response, exit with status 0 if the world spawned it."""
    options = parse_arguments(remove_ros_args(sys.argv if args is None else args)[1:])
    rclpy.init(args=args)
    node = None
    status = 1
    try:
        node = Node('spawn_model_client')
        pose = make_pose(options.x, options.y, options.z,
                         yaw=options.yaw, quaternion=options.quaternion)
        response = spawn_model(
            node, options.name, model_file=options.file, pose=pose,
            namespace=options.namespace, reference_frame=options.reference_frame,
            timeout=options.timeout)
        print(response_text(response))
        status = 0 if response.success else 1
    except (OSError, TimeoutError) as error:
        print(f'spawn_model_client: {error}', file=sys.stderr)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


if __name__ == '__main__':
    sys.exit(main())
