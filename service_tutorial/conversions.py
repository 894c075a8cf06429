"""
Conversions between ROS messages and the plain numbers of the simulation, in one place.

Simulation time is a float of seconds; builtin_interfaces/Time splits it into sec and nanosec.
MuJoCo orders a quaternion (w, x, y, z); geometry_msgs/Quaternion is written (x, y, z, w) on
command lines and in ROS tools. Every function here says which order it takes or gives.
"""

import array
import math

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Pose

NANOSECONDS = 1_000_000_000


def time_msg(seconds):
    """Convert simulation seconds to a new builtin_interfaces/Time."""
    return fill_time_msg(Time(), seconds)


def fill_time_msg(msg, seconds):
    """Write simulation seconds into a builtin_interfaces/Time and return it."""
    sec = int(seconds)
    nanosec = int(round((seconds - sec) * 1e9))
    if nanosec >= NANOSECONDS:
        sec += 1
        nanosec -= NANOSECONDS
    msg.sec, msg.nanosec = sec, nanosec
    return msg


def fill_joint_state_msg(msg, seconds, joint_state):
    """Fill a sensor_msgs/JointState with (names, positions, velocities) at simulation seconds."""
    names, positions, velocities = joint_state
    fill_time_msg(msg.header.stamp, seconds)
    msg.name = names
    msg.position = positions.tolist()
    msg.velocity = velocities.tolist()
    return msg


def seconds_of(stamp):
    """Convert a builtin_interfaces/Time to seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def quaternion_from_msg(quaternion):
    """Return a geometry_msgs/Quaternion as a MuJoCo (w, x, y, z) tuple."""
    return (quaternion.w, quaternion.x, quaternion.y, quaternion.z)


def fill_quaternion_msg(quaternion, orientation):
    """Write a MuJoCo (w, x, y, z) quaternion into a geometry_msgs/Quaternion."""
    quaternion.w, quaternion.x, quaternion.y, quaternion.z = (float(v) for v in orientation)


def yaw_of(orientation):
    """Return the heading (rotation about z, in rad) of a geometry_msgs/Quaternion."""
    w, x, y, z = quaternion_from_msg(orientation)
    # This form needs no unit quaternion: the lesson's (0, 0, -0.707, 0.707) gives -pi/2.
    return math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z)


def pose_from_msg(pose):
    """Split a geometry_msgs/Pose into a position and a MuJoCo (w, x, y, z) quaternion."""
    position = pose.position
    return ((position.x, position.y, position.z), quaternion_from_msg(pose.orientation))


def fill_pose_msg(pose, position, orientation):
    """Write a position and a MuJoCo (w, x, y, z) quaternion into a geometry_msgs/Pose."""
    pose.position.x, pose.position.y, pose.position.z = (float(v) for v in position)
    fill_quaternion_msg(pose.orientation, orientation)
    return pose


def fill_transform_msg(transform, position, orientation):
    """Write a position and a MuJoCo (w, x, y, z) quaternion into a geometry_msgs/Transform."""
    translation = transform.translation
    translation.x, translation.y, translation.z = (float(v) for v in position)
    fill_quaternion_msg(transform.rotation, orientation)
    return transform


def make_pose(x=0.0, y=0.0, z=0.0, *, yaw=None, quaternion=None):
    """Build a geometry_msgs/Pose from a position and a yaw or an (x, y, z, w) quaternion."""
    if yaw is not None and quaternion is not None:
        raise ValueError('give the orientation as yaw or as quaternion, not both')
    if quaternion is None:
        half = 0.0 if yaw is None else yaw / 2.0
        orientation = (math.cos(half), 0.0, 0.0, math.sin(half))
    else:
        qx, qy, qz, qw = quaternion
        orientation = (qw, qx, qy, qz)
    return fill_pose_msg(Pose(), (x, y, z), orientation)


def twist_from_msg(twist):
    """Split a geometry_msgs/Twist into its linear and angular velocity vectors."""
    linear, angular = twist.linear, twist.angular
    return (linear.x, linear.y, linear.z), (angular.x, angular.y, angular.z)


def fill_twist_msg(twist, linear, angular):
    """Write linear and angular velocity vectors into a geometry_msgs/Twist."""
    twist.linear.x, twist.linear.y, twist.linear.z = (float(v) for v in linear)
    twist.angular.x, twist.angular.y, twist.angular.z = (float(v) for v in angular)
    return twist


def pixel_bytes(pixels):
    """
    Return an image's pixels (a contiguous numpy array) as a sensor_msgs/Image's data.

    The message takes an array.array of bytes as it is; bytes it would copy once more.
    """
    data = array.array('B')
    data.frombytes(pixels)
    return data
