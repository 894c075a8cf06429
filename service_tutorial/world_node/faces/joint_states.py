"""
A joint state publisher's face (gazebo_ros_joint_state_publisher): sensor_msgs/JointState.

It publishes on `joint_states` under the model's namespace, as gazebo_ros puts the plugin's
topic, each time the node's joint states stream falls due, and only while someone listens.
"""

from rclpy.event_handler import PublisherEventCallbacks
from sensor_msgs.msg import JointState
from service_tutorial.conversions import fill_joint_state_msg
from service_tutorial.sim.plugins.joint_state_publisher import JointStatePublisher
from service_tutorial.world_node.faces.face import PluginFace
from service_tutorial.world_node.pacing import JOINT_STATES_STREAM
from service_tutorial.world_node.ros_names import plugin_topic
from service_tutorial.world_node.subscribers import SubscriberWatch


class JointStatesFace(PluginFace):
    """A joint state publisher's sensor_msgs/JointState on joint_states."""

    streams = (JOINT_STATES_STREAM,)

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is gazebo_ros's joint state publisher (gz's has its own face)."""
        return isinstance(plugin, JointStatePublisher) and not plugin.is_gz_system

    def __init__(self, node, world, model, plugin, namespace):
        """Name the topic; namespace is the model's, normalised ('' or '/a/b')."""
        self.node = node
        self.publisher = plugin
        self.topics = (plugin_topic(plugin.block, 'joint_states', robot_namespace=namespace),)
        self.joint_states_pub = self.joint_states_msg = self.watch = None

    def make_topics(self):
        """Make the joint_states topic."""
        # Filled in and published again every time: publish() copies the message.
        self.joint_states_msg = JointState()
        self.joint_states_pub = self.node.create_publisher(
            JointState, self.topics[0], 10,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self.watch = SubscriberWatch(self.joint_states_pub)

    def publish(self, stream, now):
        """Publish the joints' positions and velocities at simulation time now, if wanted."""
        if not self.watch.listened():
            return
        self.joint_states_pub.publish(fill_joint_state_msg(
            self.joint_states_msg, now, self.publisher.joint_state()))

    def destroy(self):
        """Remove the topic from the node."""
        if self.joint_states_pub is not None:
            self.node.destroy_publisher(self.joint_states_pub)
            self.joint_states_pub = None
