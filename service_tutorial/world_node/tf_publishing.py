"""
What RViz and robot_state_publisher need from the world: /tf and each robot's description.

The node has one /tf publisher for every drive's odometry transform (faces/odom_tf.py):
TransformBatch, on the absolute /tf whatever the node's namespace. The transforms of one turn
go out in one TFMessage, as robot_state_publisher sends a robot's: a fleet's would otherwise be
a message per robot.

RobotDescriptionPublisher sends a model's URDF text once on `<namespace>/robot_description`
(std_msgs/String), transient local with depth 1 as robot_state_publisher does, so a subscriber
that comes later (RViz, robot_state_publisher) still gets it.
"""

from rclpy.event_handler import PublisherEventCallbacks
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
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


class RobotDescriptionPublisher:
    """A model's URDF on `<namespace>/robot_description`, latched for late subscribers."""

    def __init__(self, node, namespace, urdf):
        """Name the topic (namespace normalised: '' or '/a/b'); make_topics() makes it."""
        self.node = node
        self.topics = (topic_prefix(namespace) + 'robot_description',)
        if isinstance(urdf, bytes):
            urdf = urdf.decode('utf-8', errors='replace')
        self.urdf = urdf
        self.robot_description_pub = None

    def make_topics(self):
        """Make the topic and publish the URDF text once."""
        # One per robot: without rclpy's default event handlers it costs the executor nothing.
        self.robot_description_pub = self.node.create_publisher(
            String, self.topics[0], LATCHED_QOS,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self.robot_description_pub.publish(String(data=self.urdf))

    def destroy(self):
        """Remove the topic from the node, if make_topics() made it."""
        if self.robot_description_pub is not None:
            self.node.destroy_publisher(self.robot_description_pub)
            self.robot_description_pub = None
