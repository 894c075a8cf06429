"""Start the MuJoCo world on simulation time, and optionally the turning server and RViz."""

import os

from ament_index_python.packages import get_package_prefix, get_package_share_directory
from ament_index_python.packages import PackageNotFoundError
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, LogInfo, OpaqueFunction
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue
from launch_ros.substitutions import FindPackageShare

PACKAGE = 'service_tutorial'
# RViz's displays name absolute topics (config/world.rviz); in a namespace they follow it.
RVIZ_TOPICS = ('/robot_description', '/odom', '/scan', '/mujoco/camera/image_raw')
# The world publishes each robot's robot_description itself: robot_state_publisher's copy of
# the same text goes aside, so that the topic has one publisher.
RSP_DESCRIPTION_REMAP = ('robot_description', 'robot_state_publisher/robot_description')


def installed(package):
    """Tell whether the ament index knows a ROS package."""
    try:
        get_package_prefix(package)
    except PackageNotFoundError:
        return False
    return True


def sim_time():
    """Return the use_sim_time launch argument as a typed parameter value."""
    return ParameterValue(LaunchConfiguration('use_sim_time'), value_type=bool)


def start_rviz(context, namespace):
    """Start RViz and robot_state_publisher for tinybot, or say in one line what is missing."""
    if not IfCondition(LaunchConfiguration('rviz')).evaluate(context):
        return []
    missing = [package for package in ('rviz2', 'robot_state_publisher')
               if not installed(package)]
    if missing:
        apt = ' '.join('ros-jazzy-' + package.replace('_', '-') for package in missing)
        return [LogInfo(msg=f'rviz:=true, but {" and ".join(missing)} is not installed '
                            f'(sudo apt install {apt}): starting without RViz')]
    share = get_package_share_directory(PACKAGE)
    with open(os.path.join(share, 'models', 'tinybot.urdf')) as urdf_file:
        tinybot = urdf_file.read()
    return [
        # Places tinybot's links on /tf and /tf_static from its joint_states; the world gives
        # odom -> base_footprint on /tf and tinybot's URDF on robot_description.
        Node(
            package='robot_state_publisher',
            executable='robot_state_publisher',
            namespace=namespace,
            output='screen',
            parameters=[{
                'robot_description': ParameterValue(tinybot, value_type=str),
                'use_sim_time': sim_time(),
            }],
            remappings=[RSP_DESCRIPTION_REMAP],
        ),
        Node(
            package='rviz2',
            executable='rviz2',
            name='rviz2',
            namespace=namespace,
            output='screen',
            arguments=['-d', os.path.join(share, 'config', 'world.rviz')],
            parameters=[{'use_sim_time': sim_time()}],
            remappings=[(topic, topic.lstrip('/')) for topic in RVIZ_TOPICS],
        ),
    ]


def generate_launch_description():
    """Declare the arguments and the nodes: world, turning server, RViz."""
    params_file = LaunchConfiguration('params_file')
    namespace = LaunchConfiguration('namespace')
    return LaunchDescription([
        DeclareLaunchArgument(
            'params_file',
            default_value=PathJoinSubstitution(
                [FindPackageShare(PACKAGE), 'config', 'world.yaml']),
            description='Parameters of the world node (key: mujoco, or /**/mujoco in a '
                        'namespace); the arguments below override what it says'),
        DeclareLaunchArgument(
            'namespace', default_value='',
            description='Namespace of every node started here'),
        DeclareLaunchArgument(
            'use_sim_time', default_value='true',
            description='Run the nodes on the /clock of the world'),
        DeclareLaunchArgument(
            'gui', default_value='false',
            description="Show MuJoCo's viewer (needs a display)"),
        DeclareLaunchArgument(
            'web', default_value='false',
            description="Serve a web page with the world in 3D, live, and the lesson's buttons"),
        DeclareLaunchArgument(
            'web_port', default_value='8080',
            description='Port of the web page (the next free one if taken)'),
        DeclareLaunchArgument(
            'web_host', default_value='127.0.0.1',
            description="Address of the web page: '127.0.0.1' for this machine only, "
                        "'0.0.0.0' for every network it is on"),
        DeclareLaunchArgument(
            'real_time_factor', default_value='1.0',
            description='Simulated seconds per wall second; 0 runs as fast as it can'),
        DeclareLaunchArgument(
            'turning_server', default_value='false',
            description='Also start robot_turning_server'),
        DeclareLaunchArgument(
            'rviz', default_value='false',
            description='Also start RViz (config/world.rviz) and robot_state_publisher'),
        Node(
            package=PACKAGE,
            executable='mujoco_world',
            name='mujoco',
            namespace=namespace,
            output='screen',
            parameters=[params_file, {
                'use_sim_time': sim_time(),
                'gui': ParameterValue(LaunchConfiguration('gui'), value_type=bool),
                'real_time_factor': ParameterValue(
                    LaunchConfiguration('real_time_factor'), value_type=float),
                'web': ParameterValue(LaunchConfiguration('web'), value_type=bool),
                'web_port': ParameterValue(LaunchConfiguration('web_port'), value_type=int),
                'web_host': ParameterValue(LaunchConfiguration('web_host'), value_type=str),
            }],
        ),
        Node(
            package=PACKAGE,
            executable='robot_turning_server',
            name='robot_turning_server',
            namespace=namespace,
            output='screen',
            parameters=[{'use_sim_time': sim_time()}],
            condition=IfCondition(LaunchConfiguration('turning_server')),
        ),
        OpaqueFunction(function=start_rviz, args=[namespace]),
    ])
