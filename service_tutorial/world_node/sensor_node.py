"""
The node that publishes the robots' sensor topics, in a DDS participant of its own if it may.

Large camera frames in flight through the world node's participant would hold up its service
answers, so the sensors publish from a node of their own in a context (a DDS participant) of its
own, where participants.py allows one: beside a world in rclpy's default context. As
gazebo_ros publishes each plugin's topics from a node of the plugin's, the sensors' topics then
come from the node <world node's name>_sensors (mujoco_sensors with the default launch), in the
world node's namespace. Beside a world in a context of its own (the testing fixture's), the
world node publishes them itself. Either way the world node resolves the topic names, so its
namespace and remappings apply as to its other topics. The node is made with the first sensor
topic and never spun: it only publishes, and the faces count its topics' subscribers.
"""

import rclpy
from rclpy.event_handler import PublisherEventCallbacks
from service_tutorial.world_node.participants import sensor_context
from service_tutorial.world_node.participants import sensors_have_own_participant


class SensorNode:
    """Publishers of sensor topics, on a node of their own in a context of its own if it may."""

    def __init__(self, world_node):
        """Make nothing yet: the context and node come with the first publisher."""
        self._world_node = world_node
        # If not, the world node publishes the sensors' topics itself (participants.py).
        self._own_participant = sensors_have_own_participant(world_node.context)
        self._node = None

    @property
    def name(self):
        """Return the name the node has, or will have once a sensor topic makes it."""
        if not self._own_participant:
            return self._world_node.get_name()
        return f'{self._world_node.get_name()}_sensors'

    @property
    def publishers(self):
        """Return the publishers the node has beside the world node's own."""
        if self._node is None or not self._own_participant:
            return []
        return list(self._node.publishers)

    def create_publisher(self, msg_type, topic, depth):
        """Make a publisher of a topic, named as the world node would name it."""
        if self._node is None:
            self._start()
        # Without rclpy's two default event handlers, a publisher costs nothing more.
        return self._node.create_publisher(
            msg_type, self._world_node.resolve_topic_name(topic), depth,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))

    def destroy_publisher(self, publisher):
        """Remove a publisher this node made; after destroy(), there is nothing to remove."""
        if self._node is not None:
            self._node.destroy_publisher(publisher)

    def _start(self):
        if not self._own_participant:
            self._node = self._world_node
            return
        context = sensor_context(self._world_node.context)
        self._node = rclpy.create_node(
            self.name, namespace=self._world_node.get_namespace(), context=context,
            use_global_arguments=False, start_parameter_services=False, enable_rosout=False)

    def destroy(self):
        """Destroy the node (its context stays for the process's other worlds)."""
        if self._node is not None and self._own_participant:
            self._node.destroy_node()
        self._node = None
