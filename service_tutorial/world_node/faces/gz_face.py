"""
What the faces of gz-sim's systems share: their gz topics served as the bridge says.

A gz system knows its gz topics, named after its model and world (gz_topics() of its plugin);
the node's GzBridge (gz_bridge.py) says under which ROS name and type each is served, if at all,
and the face makes that topic on the world node, with ros_gz_bridge's QoS (depth 10, reliable,
volatile) and without rclpy's default event handlers, which would cost every executor turn.
Commands never wake the executor: the node has each face take them at its tick
(taken_at_tick.py), as the Classic drive's face does. A face described without a spawned model
(GetSpawnables) names the topics after the robot's own name and the world 'default'.
"""

from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from service_tutorial.sim.plugins.gz_names import DEFAULT_WORLD_NAME
from service_tutorial.world_node.faces.face import PluginFace
from service_tutorial.world_node.taken_at_tick import take_messages, TakenAtTick

# ros_gz_bridge's queue on both sides of a topic.
BRIDGE_DEPTH = 10


def gz_owner(world, model, plugin):
    """Return (world name, model name) a plugin's gz topics are named after."""
    world_name = world.name if world is not None else DEFAULT_WORLD_NAME
    model_name = model.name if model is not None else plugin.config.robot_name
    return world_name, model_name


class GzFace(PluginFace):
    """A gz plugin's face: the ROS topics the bridge serves its gz topics as."""

    def __init__(self, node, world, model, plugin, namespace):
        """Keep what the face serves; each kind asks the bridge for its topics."""
        self.node = node
        self.world = world
        self.model = model
        self.plugin = plugin
        self.bridge = node.gz_bridge
        self.world_name, self.model_name = gz_owner(world, model, plugin)
        self._publishers = []
        self._subscriptions = []  # (subscription, callback) of the commands taken at tick

    @property
    def topics(self):
        """Return the ROS names of the face's topics (bridged: see bridged_topics)."""
        return tuple(topic.ros_name for topic in self.bridged_topics if topic is not None)

    @property
    def bridged_topics(self):
        """Return the BridgedTopics the face serves (None for one the bridge does not)."""
        return ()

    def publisher(self, bridged):
        """Make the ROS publisher of a BridgedTopic (in make_topics), or None if it is None."""
        if bridged is None:
            return None
        publisher = self.node.create_publisher(
            bridged.ros_type, bridged.ros_name, BRIDGE_DEPTH,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self._publishers.append(publisher)
        return publisher

    def subscription(self, bridged, callback):
        """Take the commands of a BridgedTopic at each tick, handing each to callback."""
        if bridged is None:
            return
        subscription = self.node.create_subscription(
            bridged.ros_type, bridged.ros_name, callback, BRIDGE_DEPTH,
            callback_group=TakenAtTick(),
            event_callbacks=SubscriptionEventCallbacks(use_default_callbacks=False))
        self._subscriptions.append((subscription, callback))

    @property
    def takes_commands(self):
        """Tell whether the face has commands to take at each tick."""
        return bool(self._subscriptions)

    def take_commands(self):
        """Hand the commands that came since the last tick to their callbacks, in order."""
        for subscription, callback in self._subscriptions:
            for msg in take_messages(subscription):
                callback(msg)

    def destroy(self):
        """Remove the face's topics from the node."""
        for publisher in self._publishers:
            self.node.destroy_publisher(publisher)
        for subscription, _ in self._subscriptions:
            self.node.destroy_subscription(subscription)
        self._publishers, self._subscriptions = [], []
