"""Differential-drive kinematics and wheel odometry, free of any simulator or ROS."""

from dataclasses import dataclass
import math

ODOMETRY_SOURCE_ENCODER = 0
ODOMETRY_SOURCE_WORLD = 1


@dataclass(frozen=True)
class DiffDriveConfig:
    """
    Settings of a gazebo_ros diff-drive plugin, in ROS 2 names and SI units.

    Wheel joints are given in pairs; every left joint turns at the left wheel speed.
    ROS 1 legacy mode is resolved while parsing by swapping the two joint lists.
    """

    left_joints: tuple
    right_joints: tuple
    wheel_separation: float = 0.34
    wheel_diameter: float = 0.15
    max_wheel_torque: float = 5.0
    max_wheel_acceleration: float = 0.0  # m/s^2 at the wheel rim; 0 means unlimited
    odometry_frame: str = 'odom'
    robot_base_frame: str = 'base_footprint'
    odometry_source: int = ODOMETRY_SOURCE_WORLD
    command_topic: str = 'cmd_vel'
    odometry_topic: str = 'odom'
    publish_odom: bool = True
    publish_odom_tf: bool = True
    publish_wheel_tf: bool = False
    update_rate: float = 100.0
    ros_namespace: str = ''
    ros_remappings: tuple = ()
    legacy_mode: bool = False

    @property
    def wheel_radius(self):
        """Return the wheel radius in metres."""
        return self.wheel_diameter / 2.0

    @property
    def left_joint(self):
        """Return the first left wheel joint, the one encoder odometry reads."""
        return self.left_joints[0]

    @property
    def right_joint(self):
        """Return the first right wheel joint, the one encoder odometry reads."""
        return self.right_joints[0]


def wheel_speeds(linear_x, angular_z, wheel_separation, wheel_radius):
    """Return (left, right) wheel speeds in rad/s for a body twist in m/s and rad/s."""
    rim_offset = angular_z * wheel_separation / 2.0
    return ((linear_x - rim_offset) / wheel_radius, (linear_x + rim_offset) / wheel_radius)


def body_velocity(left_speed, right_speed, wheel_separation, wheel_radius):
    """Return (linear_x, angular_z) of the base for wheel speeds in rad/s."""
    linear_x = wheel_radius * (left_speed + right_speed) / 2.0
    angular_z = wheel_radius * (right_speed - left_speed) / wheel_separation
    return linear_x, angular_z


def integrate_arc(x, y, yaw, distance, turn):
    """Advance a planar pose along a circular arc of given length and heading change."""
    if abs(turn) < 1e-9:
        # Second-order midpoint step; exact in the limit of a straight line.
        heading = yaw + turn / 2.0
        return x + distance * math.cos(heading), y + distance * math.sin(heading), yaw + turn
    radius = distance / turn
    new_yaw = yaw + turn
    return (x + radius * (math.sin(new_yaw) - math.sin(yaw)),
            y - radius * (math.cos(new_yaw) - math.cos(yaw)),
            new_yaw)


class EncoderOdometry:
    """Dead reckoning of a planar pose from the angles of the two wheels."""

    def __init__(self, wheel_separation, wheel_radius):
        """Start at the origin with both wheel angles at zero."""
        self.wheel_separation = wheel_separation
        self.wheel_radius = wheel_radius
        self.reset(0.0, 0.0)

    def reset(self, left_angle, right_angle):
        """Put the pose back to the origin and remember the current wheel angles."""
        self.x = 0.0
        self.y = 0.0
        self.yaw = 0.0
        self._left_angle = left_angle
        self._right_angle = right_angle

    def update(self, left_angle, right_angle):
        """Integrate the wheel rotation since the last update as one arc."""
        left_travel = (left_angle - self._left_angle) * self.wheel_radius
        right_travel = (right_angle - self._right_angle) * self.wheel_radius
        self._left_angle = left_angle
        self._right_angle = right_angle
        distance = (left_travel + right_travel) / 2.0
        turn = (right_travel - left_travel) / self.wheel_separation
        self.x, self.y, self.yaw = integrate_arc(self.x, self.y, self.yaw, distance, turn)
