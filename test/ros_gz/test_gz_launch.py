"""
A Gazebo-style launch under launch_testing: the world, create and parameter_bridge.

The launch description is shaped as a Jazzy Gazebo launch file is (gz_sim, create, the
bridge), with the world node in place of Gazebo and this package's create and
parameter_bridge in place of ros_gz's: create spawns a robot from an installed file into an
empty world and ends with status 0, the bridge's mappings are applied in the world while it
runs, and the robot drives on cmd_vel and scans. launch and launch_testing come with a ROS 2
Jazzy install, not with the PyPI wheels: there this file skips.
"""

import os
import tempfile
import time
import unittest

from ament_index_python.packages import get_package_share_directory
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
import pytest
import rclpy
from rclpy.executors import SingleThreadedExecutor
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
BRIDGE_YAML = """\
- ros_topic_name: "cmd_vel"
  gz_topic_name: "/model/tb/cmd_vel"
  ros_type_name: "geometry_msgs/msg/TwistStamped"
  gz_type_name: "gz.msgs.Twist"
  direction: ROS_TO_GZ
"""


@pytest.mark.launch_test
def generate_test_description():
    """Launch an empty world, spawn the lesson's tinybot with create, and run a bridge."""
    config = os.path.join(tempfile.mkdtemp(prefix='gz_launch_'), 'tb_bridge.yaml')
    with open(config, 'w', encoding='utf-8') as config_file:
        config_file.write(BRIDGE_YAML)
    robot = os.path.join(get_package_share_directory(PACKAGE), 'models', 'tinybot.urdf')
    world = Node(package=PACKAGE, executable='mujoco_world', output='screen',
                 parameters=[{'world': 'empty', 'real_time_factor': 0.0}])
    create = Node(package=PACKAGE, executable='create', output='screen',
                  arguments=['-name', 'tb', '-file', robot, '-x', '0.5', '-z', '0.01'])
    bridge = Node(package=PACKAGE, executable='parameter_bridge', output='screen',
                  parameters=[{'config_file': config}])
    return LaunchDescription([world, create, bridge, launch_testing.actions.ReadyToTest()]), {
        'world': world, 'create': create, 'bridge': bridge}


class TestTheGazeboStyleLaunch(unittest.TestCase):
    """The robot as a Jazzy user meets it once the launch runs."""

    @classmethod
    def setUpClass(cls):
        # A context of its own: other tests of the session may hold rclpy's default one.
        cls.context = rclpy.Context()
        rclpy.init(context=cls.context)
        cls.node = rclpy.create_node('gz_launch_test', context=cls.context)
        cls.executor = SingleThreadedExecutor(context=cls.context)
        cls.executor.add_node(cls.node)

    @classmethod
    def tearDownClass(cls):
        cls.executor.shutdown()
        cls.node.destroy_node()
        rclpy.try_shutdown(context=cls.context)

    def spin_until(self, predicate, timeout):
        deadline = time.monotonic() + timeout
        while not predicate() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.1)
        return predicate()

    def test_create_spawns_the_robot_and_ends_with_status_0(self, proc_info, proc_output, create):
        proc_output.assertWaitFor("spawned 'tb'", process=create, timeout=START_UP_TIMEOUT)
        proc_info.assertWaitForShutdown(process=create, timeout=START_UP_TIMEOUT)
        launch_testing.asserts.assertExitCodes(proc_info, process=create)

    def test_the_world_applies_the_bridges_mappings(self, proc_output, world):
        proc_output.assertWaitFor('bridge /ros_gz_bridge: 1 mapping(s) applied', process=world,
                                  timeout=START_UP_TIMEOUT)

    def test_the_robot_drives_on_cmd_vel_and_scans(self):
        odometry, scans = [], []
        self.node.create_subscription(Odometry, '/odom', odometry.append, 10)
        self.node.create_subscription(LaserScan, '/scan', scans.append, 10)
        self.assertTrue(self.spin_until(lambda: odometry and scans, START_UP_TIMEOUT),
                        'no odometry or scan')
        start = odometry[-1].pose.pose.position.x
        command = self.node.create_publisher(Twist, '/cmd_vel', 10)
        forward = Twist()
        forward.linear.x = 0.3

        def moved():
            command.publish(forward)
            return odometry[-1].pose.pose.position.x - start > 0.1
        self.assertTrue(self.spin_until(moved, START_UP_TIMEOUT), 'the robot did not drive')
        self.assertGreater(len(scans[-1].ranges), 0)


@launch_testing.post_shutdown_test()
class TestAfterTheLaunch(unittest.TestCase):
    """What the processes left behind once launch_testing stopped them."""

    def test_every_process_ended_cleanly(self, proc_info):
        launch_testing.asserts.assertExitCodes(proc_info)
