"""
A Gazebo-style launch under launch_testing: the world, create and parameter_bridge.

The launch description is shaped as a Jazzy Gazebo launch file is (gz_sim, create, the
bridge), with the world node in place of Gazebo and this package's create and
parameter_bridge in place of ros_gz's, as TurtleBot3's Jazzy launch brings up its burger: create
spawns the suite's burger (an SDF model with gz-sim's DiffDrive, JointStatePublisher, a lidar
and an IMU) and a wall 1.45 m ahead of it into an empty world and ends with status 0, the
bridge's mappings (turtlebot3_burger_bridge.yaml's entries) are applied in the world while it
runs, and the robot reads the wall in its scan and drives on the bridged cmd_vel, a
TwistStamped. launch and launch_testing come with a ROS 2
Jazzy install, not with the PyPI wheels: there this file skips.
"""

import os
import unittest

from geometry_msgs.msg import TwistStamped
from launched_graph import LaunchedGraphTestCase
from nav_msgs.msg import Odometry
import pytest
from sensor_msgs.msg import LaserScan

try:
    from launch import LaunchDescription
    from launch_ros.actions import Node
    import launch_testing.actions
    import launch_testing.asserts
except ImportError:
    pytest.skip('launch_testing is not installed (launch is not on PyPI)',
                allow_module_level=True)

# A busy machine may take this long to start the world and spawn the robot.
START_UP_TIMEOUT = 60.0
PACKAGE = 'service_tutorial'
BURGER = os.path.join(os.path.dirname(__file__), '..', 'models', 'sdf', 'models', 'burger',
                      'model.sdf')
# The face of a static wall, m ahead on x; the burger's lidar stands 0.032 m behind its origin.
WALL = 1.45
LIDAR_X = -0.032
WALL_SDF = """<sdf version="1.9"><model name="wall"><static>true</static><link name="wall">
<collision name="wall"><geometry><box><size>0.1 4 1</size></box></geometry></collision>
</link></model></sdf>"""
# turtlebot3_simulations' Jazzy bridge file for the burger, less its clock (the world
# publishes /clock itself).
BRIDGE_FILE = os.path.join(os.path.dirname(__file__), '..', 'models', 'sdf',
                           'turtlebot3_burger_bridge.yaml')


@pytest.mark.launch_test
def generate_test_description():
    """Launch an empty world, spawn the burger and a wall with create, and run its bridge."""
    with open(BURGER, encoding='utf-8') as burger_file:
        burger = burger_file.read()
    world = Node(package=PACKAGE, executable='mujoco_world', output='screen',
                 parameters=[{'world': 'empty', 'real_time_factor': 0.0}])
    # -string, as the suite's burger is no installed file (create -file reads package shares).
    create = Node(package=PACKAGE, executable='create', output='screen',
                  arguments=['-name', 'burger', '-string', burger, '-z', '0.01'])
    create_wall = Node(package=PACKAGE, executable='create', output='screen',
                       arguments=['-name', 'wall', '-string', WALL_SDF,
                                  '-x', str(WALL + 0.05), '-z', '0.5'])
    bridge = Node(package=PACKAGE, executable='parameter_bridge', output='screen',
                  parameters=[{'config_file': os.path.abspath(BRIDGE_FILE)}])
    return LaunchDescription([world, create, create_wall, bridge,
                              launch_testing.actions.ReadyToTest()]), {
        'world': world, 'create': create, 'create_wall': create_wall, 'bridge': bridge}


class TestTheGazeboStyleLaunch(LaunchedGraphTestCase):
    """The robot as a Jazzy user meets it once the launch runs."""

    node_name = 'gz_launch_test'

    def test_create_spawns_the_robot_and_ends_with_status_0(
            self, proc_info, proc_output, create, create_wall):
        proc_output.assertWaitFor("spawned 'burger'", process=create,
                                  timeout=START_UP_TIMEOUT)
        # Both creates end on their own, before the launch's end could interrupt the wall's.
        for program in (create, create_wall):
            proc_info.assertWaitForShutdown(process=program, timeout=START_UP_TIMEOUT)
            launch_testing.asserts.assertExitCodes(proc_info, process=program)

    def test_the_world_applies_the_bridges_mappings(self, proc_output, world):
        proc_output.assertWaitFor('bridge /ros_gz_bridge: 6 mapping(s) applied', process=world,
                                  timeout=START_UP_TIMEOUT)

    def test_the_robot_scans_the_wall_and_drives_on_the_bridged_cmd_vel(self):
        odometry, scans = [], []
        self.node.create_subscription(Odometry, '/odom', odometry.append, 10)
        self.node.create_subscription(LaserScan, '/scan', scans.append, 10)
        # A scan that sees the wall: the wall may come after the robot.
        self.assertTrue(self.spin_until(lambda: odometry and scans and scans[-1].ranges[0] < 3,
                                        START_UP_TIMEOUT),
                        f'{len(odometry)} odometry messages, {len(scans)} scans, the last '
                        f'reading {scans[-1].ranges[0] if scans else None} m ahead')
        start = odometry[-1].pose.pose.position.x
        # The beams about straight ahead (0 rad, and 1 degree either side), 1 cm noise each.
        ahead = [scans[-1].ranges[i] for i in (-1, 0, 1)]
        expected = WALL - (start + LIDAR_X)
        print(f'\nburger: the wall {expected:.4f} m ahead reads {sum(ahead) / 3:.4f} m')
        self.assertAlmostEqual(sum(ahead) / 3, expected, delta=0.02)
        command = self.node.create_publisher(TwistStamped, '/cmd_vel', 10)
        forward = TwistStamped()
        forward.twist.linear.x = 0.2

        def moved():
            command.publish(forward)
            return odometry[-1].pose.pose.position.x - start > 0.1
        self.assertTrue(self.spin_until(moved, START_UP_TIMEOUT), 'the robot did not drive')


@launch_testing.post_shutdown_test()
class TestAfterTheLaunch(unittest.TestCase):
    """What the processes left behind once launch_testing stopped them."""

    def test_every_process_ended_cleanly(self, proc_info):
        launch_testing.asserts.assertExitCodes(proc_info)
