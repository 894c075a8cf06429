"""
gz-sim's JointStatePublisher as ROS sees it: sensor_msgs/JointState on its gz topic.

The topic is /world/<world>/model/<model>/joint_state, or the block's <topic>, served as the
node's bridge says; each joint has its position, velocity and effort, as ros_gz_bridge turns
gz's Model message into a JointState. It goes out each time the node's joint states stream
falls due, and only while someone listens.
"""

from sensor_msgs.msg import JointState
from service_tutorial.conversions import fill_joint_state_msg
from service_tutorial.sim.plugins.gz_joint_state_publisher import GzJointStatePublisher
from service_tutorial.world_node.faces.gz_face import GzFace
from service_tutorial.world_node.gz_bridge import GZ_TO_ROS
from service_tutorial.world_node.pacing import JOINT_STATES_STREAM


class GzJointStatesFace(GzFace):
    """A JointStatePublisher's joint states, as the bridge serves them."""

    streams = (JOINT_STATES_STREAM,)

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is gz-sim's JointStatePublisher."""
        return isinstance(plugin, GzJointStatePublisher)

    def gz_topics(self):
        """Return the publisher's gz topic with its gz type."""
        name = self.plugin.gz_topics(self.model_name, self.world_name)['joint_state']
        return {'joint_state': (name, 'gz.msgs.Model', GZ_TO_ROS)}

    def make_topics(self):
        """Make the joint states topic."""
        self.publisher('joint_state')
        self.joint_state_msg = JointState()

    def publish(self, stream, now):
        """Publish the joints' states at simulation time now, if anyone listens."""
        publisher = self.listened('joint_state')
        if publisher is None:
            return
        msg = fill_joint_state_msg(self.joint_state_msg, now, self.plugin.joint_state())
        msg.effort = self.plugin.joint_efforts().tolist()
        publisher.publish(msg)
