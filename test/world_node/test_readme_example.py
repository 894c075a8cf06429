"""A test of a node of your own: tinybot drives one metre on its odometry, then stops."""

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
import pytest
from rclpy.node import Node

pytest_plugins = ['service_tutorial.testing.fixtures']


class DriveDistance(Node):
    """Drive ahead on cmd_vel until odom says the robot went distance metres, then stop."""

    def __init__(self, distance, **kwargs):
        super().__init__('drive_distance', **kwargs)
        self.distance = distance
        self.start_x = None
        self.cmd_vel_pub = self.create_publisher(Twist, 'cmd_vel', 10)
        self.odom_sub = self.create_subscription(Odometry, 'odom', self.odom_callback, 10)

    def odom_callback(self, odom):
        x = odom.pose.pose.position.x
        self.start_x = x if self.start_x is None else self.start_x
        command = Twist()
        command.linear.x = 0.3 if x - self.start_x < self.distance else 0.0
        self.cmd_vel_pub.publish(command)


def test_tinybot_stops_one_metre_ahead(mujoco_sim):
    mujoco_sim.add_node(DriveDistance(1.0, context=mujoco_sim.context))
    for _ in range(250):  # 5 s of simulation time, 10 steps of 2 ms at a time
        mujoco_sim.step(10)
    assert mujoco_sim.time == pytest.approx(5.0)
    tinybot = mujoco_sim.entity_state('tinybot')  # the ground truth, not the odometry
    assert 1.0 < tinybot.pose.position.x < 1.06  # one metre, then braking to a stop
    assert tinybot.twist.linear.x == pytest.approx(0.0, abs=1e-3)
