"""
The node that publishes the robots' sensor topics, in a DDS participant of its own.

A 2048x2048 camera frame is 12 MB on a reliable topic: hundreds of fragments. Sent through the
world node's own participant, frames in flight held up its service answers: in the sensor storm
of scripts/stress, answers the world had sent at once reached eight clients together 1.3 to 3 s
later, while /clock kept coming. Published by a node in a context of its own (a participant
with its own sockets, shared memory and sending thread), they leave the answers' way clear: the
storm's p99 answer time went from 1.7 s to 0.15 s.

As gazebo_ros publishes each plugin's topics from a node of the plugin's, the sensors' topics
come from the node <world node's name>_sensors (mujoco_sensors with the default launch), in the
world node's namespace. The world node resolves the topic names, so its namespace and
remappings apply as to its other topics. The node is made with the first sensor topic and never
spun: it only publishes, and the faces count its topics' subscribers.

The sensors' context lives as long as the world node's context: one per world context, made
with the first sensor topic and ended when the world's context shuts down. Fast DDS 2.14 can
hang deleting a participant while another participant of the same process and domain delivers
discovery data to it (seen in the test suite: rmw's set_listener(nullptr) spun for good while a
discovery callback waited for its mutex). rmw deletes a context's participant with the
context's last node, so both participants are held by a hidden node each
(_sensors_participant, _sensors_neighbour in the world's context) while world nodes and a
test's nodes come and go; without the second, each test that ended with its world deleted the
world context's participant beside the sensors'. At shutdown the sensors' participant goes
first, then the world's hidden node: one deletion beside a neighbour per process, not one per
test. A test's own context on the same domain is still a neighbour, which is why the testing
fixture's worlds, each alone on its domain, publish their sensors' topics from the world node
(MujocoWorld(sensor_participant=False)).
"""

import atexit
import threading

import rclpy
from rclpy.context import Context
from rclpy.event_handler import PublisherEventCallbacks

_lock = threading.Lock()
_contexts = {}  # id of a world's context -> (the sensors' Context, the node keeping it up)


def _sensor_context(world_context):
    """Return the sensors' context beside a world's context, made once."""
    key = id(world_context)
    with _lock:
        if key not in _contexts:
            context = Context()
            # No command-line arguments: a node rename given to the world must not name these.
            context.init(args=[], initialize_logging=False,
                         domain_id=world_context.get_domain_id())
            # Hidden (a leading underscore): `ros2 node list --all` shows it.
            keepers = tuple(rclpy.create_node(
                name, context=kept, use_global_arguments=False,
                start_parameter_services=False, enable_rosout=False)
                for name, kept in (('_sensors_participant', context),
                                   ('_sensors_neighbour', world_context)))
            _contexts[key] = (context, keepers)
            world_context.on_shutdown(lambda: _end_sensor_context(key))
        return _contexts[key][0]


def _end_sensor_context(key):
    with _lock:
        context, keepers = _contexts.pop(key, (None, ()))
    if context is not None:
        sensors_keeper, world_keeper = keepers
        sensors_keeper.destroy_node()
        context.try_shutdown()
        world_keeper.destroy_node()  # the last participant of the domain here, if no other


@atexit.register
def _end_sensor_contexts():
    for key in list(_contexts):
        _end_sensor_context(key)


class SensorNode:
    """Publishers of sensor topics, on a node of their own in a context of its own."""

    def __init__(self, world_node, *, own_participant=True):
        """
        Make nothing yet: the context and node come with the first publisher.

        own_participant False: the world node publishes the sensors' topics itself (the
        testing fixture's worlds, each alone on its domain, whose one participant then goes
        with its context).
        """
        self._world_node = world_node
        self._own_participant = own_participant
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
        context = _sensor_context(self._world_node.context)
        self._node = rclpy.create_node(
            self.name, namespace=self._world_node.get_namespace(), context=context,
            use_global_arguments=False, start_parameter_services=False, enable_rosout=False)

    def destroy(self):
        """Destroy the node (its context stays for the process's other worlds)."""
        if self._node is not None and self._own_participant:
            self._node.destroy_node()
        self._node = None
