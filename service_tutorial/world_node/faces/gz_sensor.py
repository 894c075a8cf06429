"""
What the faces of gz-sim's sensors share: the bridge's topics, switched by their subscribers.

A gz sensor's face is a GzFace (its gz topics served as the node's bridge says, re-made when
the bridge changes) and a SensorFace (the sensor measures only while one of its topics is
listened to, its readings published from the world's sensor node, stamped with simulation
time). Each kind (gz_lidar.py, gz_camera.py, gz_imu.py, gz_navsat.py) names its topics by role
and fills their messages.
"""

import numpy as np
from service_tutorial.conversions import pixel_bytes
from service_tutorial.sim.plugins import Plugin
from service_tutorial.world_node.faces.gz_face import BRIDGE_DEPTH, GzFace
from service_tutorial.world_node.faces.sensor import SensorFace
from service_tutorial.world_node.gz_bridge import GZ_TO_ROS
from service_tutorial.world_node.subscribers import SubscriberWatch


def data_of(values):
    """Return a numpy array's bytes (floats, records...) as a message's uint8[] data."""
    return pixel_bytes(np.ascontiguousarray(values).reshape(-1).view(np.uint8))


class GzSensorFace(GzFace, SensorFace, sensor_type=Plugin):
    """A gz sensor's topics, as the bridge serves them; subscribers switch it on and off."""

    gz_types = {}  # role -> gz message type, for each kind

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is a gz sensor of this face's kind."""
        return isinstance(plugin, cls.sensor_type) and plugin.is_gz_system

    def __init__(self, node, world, model, plugin, namespace):
        """Ask the bridge how the sensor's topics are served; name the frame."""
        SensorFace.__init__(self, node, world, model, plugin, namespace)
        GzFace.__init__(self, node, world, model, plugin, namespace)
        self.frame = plugin.gz_frame(self.model_name)

    def gz_topics(self):
        """Return the sensor's gz topics (None: not published) with their gz types."""
        names = self.sensor.gz_topics(self.model_name, self.world_name)
        return {role: (name, self.gz_types[role], GZ_TO_ROS) for role, name in names.items()}

    def create_publisher(self, bridged):
        """Make a publisher of a BridgedTopic on the sensor node; its subscribers count."""
        publisher = self.node.sensor_node.create_publisher(bridged.ros_type, bridged.ros_name,
                                                           BRIDGE_DEPTH)
        self.watch.add(publisher)
        return publisher

    def destroy_publisher(self, publisher):
        """Remove a publisher from the sensor node."""
        self.node.sensor_node.destroy_publisher(publisher)

    def destroy_topics(self):
        """Remove the topics; the sensor stops until someone listens to the new ones."""
        super().destroy_topics()
        self.watch = SubscriberWatch()
        self.next_look = 0.0

    def destroy(self):
        """Stop the sensor and remove its topics."""
        self.sensor.listener = None
        self.sensor.set_active(False)
        self.destroy_topics()
