"""
gz-sim's OdometryPublisher as ROS sees it: ground-truth odometry, with covariance, and its pose.

Its gz topics (/model/<model>/odometry, /odometry_with_covariance and /pose, or the block's)
are served as the node's bridge says; each goes out at the publisher's rate of simulation time,
stamped with it, in its frames. ros_gz_bridge gives the plain odometry zero covariances and the
other the variance of the publisher's noise; the pose goes out as a TFMessage.
"""

from nav_msgs.msg import Odometry
from service_tutorial.sim.plugins.gz_odometry_publisher import GzOdometryPublisher
from service_tutorial.world_node.faces.gz_diff_drive import fill_odometry_msg, tf_msg
from service_tutorial.world_node.faces.gz_face import GzFace
from service_tutorial.world_node.gz_bridge import GZ_TO_ROS


class GzOdometryFace(GzFace):
    """An OdometryPublisher's odometry, odometry with covariance and pose, as bridged."""

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is gz-sim's OdometryPublisher."""
        return isinstance(plugin, GzOdometryPublisher)

    def gz_topics(self):
        """Return the publisher's gz topics with their gz types."""
        names = self.plugin.gz_topics(self.model_name)
        return {'odometry': (names['odometry'], 'gz.msgs.Odometry', GZ_TO_ROS),
                'odometry_with_covariance': (names['odometry_with_covariance'],
                                             'gz.msgs.OdometryWithCovariance', GZ_TO_ROS),
                'tf': (names['tf'], 'gz.msgs.Pose_V', GZ_TO_ROS)}

    def make_topics(self):
        """Make the topics; publish at each update of the publisher."""
        for role in self.served:
            self.publisher(role)
        self.odom_msg, self.covariance_msg = Odometry(), Odometry()
        variance = float(self.plugin.covariance)
        for index in range(6):  # the noise's variance on both diagonals
            self.covariance_msg.pose.covariance[7 * index] = variance
            self.covariance_msg.twist.covariance[7 * index] = variance
        self.plugin.listener = self.odometry_callback

    def odometry_callback(self, publisher):
        """Publish the ground truth on each topic someone listens to."""
        wanted = {role: self.listened(role) for role in self.served}
        if not any(wanted.values()):
            return
        now, odometry = self.world.time, publisher.odometry()
        if wanted['odometry'] is not None:
            wanted['odometry'].publish(fill_odometry_msg(self.odom_msg, now, odometry))
        if wanted['odometry_with_covariance'] is not None:
            wanted['odometry_with_covariance'].publish(
                fill_odometry_msg(self.covariance_msg, now, odometry))
        if wanted['tf'] is not None:
            wanted['tf'].publish(tf_msg(now, odometry))

    def destroy_topics(self):
        """Stop publishing, and remove the topics."""
        self.plugin.listener = None
        super().destroy_topics()
