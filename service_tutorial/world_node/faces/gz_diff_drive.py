"""
gz-sim's DiffDrive as ROS sees it through ros_gz_bridge: cmd_vel in, odometry and tf out.

Its gz topics (/model/<model>/cmd_vel, /enable, /odometry, /tf, or the block's) are served as
the node's bridge says: by default under the same names, a command as geometry_msgs/Twist, or
TwistStamped where a mapping says so. Odometry and its transform go out each time the drive
integrates its wheels (odom_publish_frequency of simulation time), stamped with that time, in
the drive's frames; the transform is a TFMessage on the tf topic (/tf for TurtleBot3), as the
bridge turns gz's Pose_V into one.
"""

from geometry_msgs.msg import TransformStamped
from nav_msgs.msg import Odometry
from service_tutorial.conversions import fill_pose_msg, fill_time_msg, fill_transform_msg
from service_tutorial.conversions import fill_twist_msg
from service_tutorial.sim.plugins.gz_diff_drive import GzDiffDrive
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.faces.gz_face import GzFace
from service_tutorial.world_node.gz_bridge import GZ_TO_ROS, ROS_TO_GZ, twist_of
from tf2_msgs.msg import TFMessage


def fill_odometry_msg(msg, now, odometry):
    """Fill a nav_msgs/Odometry with an Odometry of the core at simulation time now."""
    fill_time_msg(msg.header.stamp, now)
    msg.header.frame_id = odometry.odometry_frame
    msg.child_frame_id = odometry.robot_base_frame
    fill_pose_msg(msg.pose.pose, odometry.position, odometry.orientation)
    fill_twist_msg(msg.twist.twist, odometry.linear_velocity, odometry.angular_velocity)
    return msg


def tf_msg(now, odometry):
    """Return the TFMessage of an odometry's pose: odometry frame -> robot base frame."""
    transform = TransformStamped()
    fill_time_msg(transform.header.stamp, now)
    transform.header.frame_id = odometry.odometry_frame
    transform.child_frame_id = odometry.robot_base_frame
    fill_transform_msg(transform.transform, odometry.position, odometry.orientation)
    return TFMessage(transforms=[transform])


class GzDiffDriveFace(GzFace):
    """A DiffDrive's cmd_vel and enable in, odometry and tf out, as the bridge serves them."""

    takes_commands = True

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is gz-sim's DiffDrive."""
        return isinstance(plugin, GzDiffDrive)

    def gz_topics(self):
        """Return the drive's gz topics with their gz types and directions."""
        names = self.plugin.gz_topics(self.model_name)
        return {'cmd_vel': (names['cmd_vel'], 'gz.msgs.Twist', ROS_TO_GZ),
                'enable': (names['enable'], 'gz.msgs.Boolean', ROS_TO_GZ),
                'odometry': (names['odometry'], 'gz.msgs.Odometry', GZ_TO_ROS),
                'tf': (names['tf'], 'gz.msgs.Pose_V', GZ_TO_ROS)}

    def make_topics(self):
        """Take commands, and publish odometry and tf at each odometry update of the drive."""
        self.subscription('cmd_vel', self.cmd_vel_callback)
        self.subscription('enable', self.enable_callback)
        self.publisher('odometry')
        self.publisher('tf')
        self.odom_msg = Odometry()
        self.plugin.listener = self.odometry_callback

    def cmd_vel_callback(self, msg):
        """Hand a Twist or TwistStamped command to the drive; the next steps apply it."""
        twist = twist_of(msg)
        try:
            self.plugin.command_velocity(twist.linear.x, twist.angular.z)
        except WorldError as error:
            self.warn_command('cmd_vel', error)

    def enable_callback(self, msg):
        """Enable or disable the drive (std_msgs/Bool)."""
        self.plugin.set_enabled(msg.data)

    def odometry_callback(self, drive):
        """Publish the drive's odometry and its transform, if anyone listens."""
        odom_pub, tf_pub = self.listened('odometry'), self.listened('tf')
        if odom_pub is None and tf_pub is None:
            return
        now, odometry = self.world.time, drive.odometry()
        if odom_pub is not None:
            odom_pub.publish(fill_odometry_msg(self.odom_msg, now, odometry))
        if tf_pub is not None:
            tf_pub.publish(tf_msg(now, odometry))

    def destroy_topics(self):
        """Stop publishing, and remove the topics."""
        self.plugin.listener = None
        super().destroy_topics()
