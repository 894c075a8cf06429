"""Start the MuJoCo world, and optionally the lesson's turning server, on simulation time."""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    gui = LaunchConfiguration('gui')
    real_time_factor = LaunchConfiguration('real_time_factor')
    turning_server = LaunchConfiguration('turning_server')
    return LaunchDescription([
        DeclareLaunchArgument('gui', default_value='false',
                              description="Show MuJoCo's viewer (needs a display)"),
        DeclareLaunchArgument('real_time_factor', default_value='1.0',
                              description='Simulated seconds per wall second; 0 = flat out'),
        DeclareLaunchArgument('turning_server', default_value='false',
                              description='Also start robot_turning_server'),
        Node(
            package='service_tutorial',
            executable='mujoco_world',
            name='mujoco',
            output='screen',
            parameters=[{
                'use_sim_time': True,
                'gui': gui,
                'real_time_factor': real_time_factor,
            }],
        ),
        Node(
            package='service_tutorial',
            executable='robot_turning_server',
            name='robot_turning_server',
            output='screen',
            parameters=[{'use_sim_time': True}],
            condition=IfCondition(turning_server),
        ),
    ])
