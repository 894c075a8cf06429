"""
A drive's odometry frame -> robot base frame on /tf, in step with its odom topic.

For a drive whose block asks for it (publishOdomTF / publish_odom_tf, true unless the block says
otherwise, as in Gazebo), the transform goes out each time odometry falls due, stamped with
simulation time and carrying exactly the pose that `odom` carries at that stamp. It is sent
through the node's one /tf publisher (tf_publishing.TransformBatch), so that the transforms of
one turn go out in one TFMessage; the face has no topic of its own to destroy.
"""

from geometry_msgs.msg import TransformStamped
from service_tutorial.conversions import fill_time_msg, fill_transform_msg
from service_tutorial.sim.plugins.diff_drive import DiffDrive
from service_tutorial.world_node.faces.face import PluginFace
from service_tutorial.world_node.pacing import ODOMETRY_STREAM


class OdomTfFace(PluginFace):
    """A drive's odometry frame -> robot base frame on /tf, in step with its odom topic."""

    streams = (ODOMETRY_STREAM,)

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is a gazebo_ros drive that asks for its odometry on /tf."""
        return isinstance(plugin, DiffDrive) and plugin.config.publish_odom_tf

    def __init__(self, node, world, model, plugin, namespace):
        """Send through the node's TransformBatch (node.tf_batch), whatever the namespace."""
        self.drive = plugin
        self.tf_batch = node.tf_batch
        self.transform = None

    def make_topics(self):
        """Make the message the transform goes out in, once the spawn is answered."""
        # Filled in and sent again every time: publish() copies the message.
        self.transform = TransformStamped()

    def publish(self, stream, now):
        """Queue the transform when odometry falls due at simulation time now."""
        if not self.tf_batch.wanted():
            return
        # Encoder odometry integrated a moment ago by the drive face gives the same values.
        odometry = self.drive.odometry()
        transform = self.transform
        fill_time_msg(transform.header.stamp, now)
        transform.header.frame_id = odometry.odometry_frame
        transform.child_frame_id = odometry.robot_base_frame
        fill_transform_msg(transform.transform, odometry.position, odometry.orientation)
        self.tf_batch.add(transform)
