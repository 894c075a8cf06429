"""
Spawn R2-D2 next to tinybot through /mujoco/spawn_urdf_model, as the lesson does.

The ROS 2 counterpart of the lesson's spawn_model_client.py: it reads models/r2d2.urdf from
the package share and asks the world to put it at (-2, 1, 1), turned -90 degrees about z, in the
world frame. Options choose another model, name, pose, namespace or reference frame. A xacro
file is expanded here, with --xacro-arg name:=value, before it is sent: the service takes URDF.
"""

import os
import sys

from rclpy.node import Node

from service_tutorial.conversions import make_pose
from service_tutorial.lesson.client_arguments import parse_client_arguments
from service_tutorial.lesson.model_services import model_path, response_text, spawn_model
from service_tutorial.lesson.r2d2 import R2D2_FILE, R2D2_NAME, SPAWN_POSITION, SPAWN_YAW
from service_tutorial.node_main import program_arguments, run_node
from service_tutorial.sim.robot_files import parse_xacro_arguments
from service_tutorial.sim.validation import WorldError


def add_spawn_arguments(parser):
    """Add the model, pose, namespace and frame options to the command-line parser."""
    parser.add_argument('--file', default=R2D2_FILE,
                        help="URDF or xacro file: a path, or a file name in this package's "
                             'models/ folder (default: %(default)s)')
    parser.add_argument('--xacro-arg', action='append', default=[], metavar='NAME:=VALUE',
                        help='argument for a xacro file (repeat for more)')
    parser.add_argument('--name', default=R2D2_NAME, help='model name (default: %(default)s)')
    x, y, z = SPAWN_POSITION
    parser.add_argument('-x', type=float, default=x, help='x in m (default: %(default)g)')
    parser.add_argument('-y', type=float, default=y, help='y in m (default: %(default)g)')
    parser.add_argument('-z', type=float, default=z, help='z in m (default: %(default)g)')
    orientation = parser.add_mutually_exclusive_group()
    orientation.add_argument('--yaw', type=float, help='heading in rad (default: -pi/2)')
    orientation.add_argument('--quaternion', type=float, nargs=4, metavar=('QX', 'QY', 'QZ', 'QW'),
                             help='orientation as a quaternion, instead of --yaw')
    parser.add_argument('--namespace', default='',
                        help="namespace of the model's topics (default: none)")
    parser.add_argument('--reference-frame', default='world',
                        help='frame the pose is given in (default: %(default)s)')


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    options = parse_client_arguments(
        argv, 'spawn_model_client', 'Spawn a URDF model through /mujoco/spawn_urdf_model '
        '(by default R2-D2 where the lesson puts it).', add_spawn_arguments)
    if options.yaw is None and options.quaternion is None:
        options.yaw = SPAWN_YAW
    if not os.path.isfile(options.file):
        options.file = model_path(options.file)
    return options


def split_xacro_arguments(argv):
    """
    Return argv without its '--xacro-arg name:=value' pairs, and those as '--xacro-arg=...'.

    rcl would take a bare name:=value for a remapping (a deprecated form it still accepts)
    and drop it, so the pairs are taken out before ROS sees the command line.
    """
    rest, xacro_arguments = [], []
    tokens = iter(argv)
    for token in tokens:
        if token == '--ros-args':
            rest += [token, *tokens]
        elif token == '--xacro-arg':
            value = next(tokens, None)
            if value is None:
                rest.append(token)  # argparse says that a value is missing
            else:
                xacro_arguments.append('--xacro-arg=' + value)
        else:
            rest.append(token)
    return rest, xacro_arguments


def main(args=None):
    """Spawn one model, print the response, exit with status 0 if the world spawned it."""
    args, xacro_arguments = split_xacro_arguments(sys.argv if args is None else args)
    options = parse_arguments(program_arguments(args) + xacro_arguments)

    def spawn(node):
        pose = make_pose(options.x, options.y, options.z,
                         yaw=options.yaw, quaternion=options.quaternion)
        response = spawn_model(
            node, options.name, model_file=options.file, pose=pose,
            namespace=options.namespace, reference_frame=options.reference_frame,
            xacro_arguments=parse_xacro_arguments(options.xacro_arg, path=options.file),
            timeout=options.timeout)
        print(response_text(response))
        return 0 if response.success else 1
    return run_node(lambda: Node('spawn_model_client'), spawn, args=args,
                    program='spawn_model_client',
                    errors=(OSError, WorldError, TimeoutError))


if __name__ == '__main__':
    sys.exit(main())
