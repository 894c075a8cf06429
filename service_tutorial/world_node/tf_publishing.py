"""
What RViz and robot_state_publisher need from the world: /tf and each robot's description.

OdomTfInterface is a plugin face (see model_interface.PLUGIN_INTERFACES): for a drive whose
block asks for it (publishOdomTF / publish_odom_tf, true unless the block says otherwise, as in
Gazebo), it sends the odometry frame -> robot base frame transform on /tf each time odometry
falls due, stamped with simulation time and carrying exactly the pose that `odom` carries at
that stamp. The node has one /tf publisher for all of them (TransformBatch), on the absolute
/tf whatever the node's namespace, and the transforms of one turn go out in one TFMessage, as
robot_state_publisher sends a robot's: a fleet's would otherwise be a message per robot.

RobotDescriptionPublisher sends a model's URDF text once on `<namespace>/robot_description`
(std_msgs/String), transient local with depth 1 as robot_state_publisher does, so a subscriber
that comes later (RViz, robot_state_publisher) still gets it.
"""

from geometry_msgs.msg import TransformStamped
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from service_tutorial.conversions import fill_time_msg, fill_transform_msg
from service_tutorial.world_node.pacing import ODOMETRY_STREAM
from service_tutorial.world_node.ros_names import topic_prefix
from service_tutorial.world_node.subscribers import SubscriberWatch
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

# tf2_ros's TransformBroadcaster: reliable, volatile, depth 100.
TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.VOLATILE)
# robot_state_publisher's robot_description: the latest text for every subscriber, late or not.
LATCHED_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)


class TransformBatch:
    """The node's one /tf publisher: the transforms added in one turn go out together."""

    def __init__(self, node):
        """Make the /tf publisher on node."""
        # As for every topic of the world's models: rclpy's default event handlers would add
        # two waitables to every executor turn, and a turn comes every tick.
        self.tf_pub = node.create_publisher(
            TFMessage, '/tf', TF_QOS,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self._watch = SubscriberWatch(self.tf_pub)
        self._tf_msg = TFMessage()
        self._transforms = []

    def wanted(self):
        """Tell whether anyone listens to /tf, so that transforms are worth filling in."""
        return self._watch.listened()

    def add(self, transform):
        """Queue a TransformStamped for send(); it must not change until then."""
        self._transforms.append(transform)

    def send(self):
        """Publish the queued transforms in one TFMessage, if any."""
        if self._transforms:
            self._tf_msg.transforms = self._transforms
            self.tf_pub.publish(self._tf_msg)
            self._transforms = []


class OdomTfInterface:
    """A drive's odometry frame -> robot base frame on /tf, in step with its odom topic."""

    streams = (ODOMETRY_STREAM,)

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is a drive that asks for its odometry on /tf."""
        return getattr(plugin, 'is_drive', False) and plugin.config.publish_odom_tf

    def __init__(self, node, world, model, plugin, namespace):
        """Send through the node's TransformBatch (node.tf_batch), whatever the namespace."""
        self.drive = plugin
        self.tf_batch = node.tf_batch
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

    def destroy(self):
        """Leave the shared /tf publisher to the node."""


class RobotDescriptionPublisher:
    """A model's URDF on `<namespace>/robot_description`, latched for late subscribers."""

    def __init__(self, node, namespace, urdf):
        """Publish the URDF text once; namespace is normalised ('' or '/a/b')."""
        self.node = node
        if isinstance(urdf, bytes):
            urdf = urdf.decode('utf-8', errors='replace')
        # One per robot: without rclpy's default event handlers it costs the executor nothing.
        self.robot_description_pub = node.create_publisher(
            String, topic_prefix(namespace) + 'robot_description', LATCHED_QOS,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self.robot_description_pub.publish(String(data=urdf))

    def destroy(self):
        """Remove the topic from the node."""
        self.node.destroy_publisher(self.robot_description_pub)
