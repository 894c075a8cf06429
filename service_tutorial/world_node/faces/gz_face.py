"""
What the faces of gz-sim's systems share: their gz topics served as the bridge says.

A gz system knows its gz topics, named after its model and world (gz_topics() of its plugin);
the node's GzBridge (gz_bridge.py) says under which ROS name and type each is served, if at all,
and the face makes that topic on the world node, with ros_gz_bridge's QoS (depth 10, reliable,
volatile) and without rclpy's default event handlers, which would cost every executor turn.
Commands never wake the executor: the node has each face take them at its tick
(taken_at_tick.py), as the Classic drive's face does. A face described without a spawned model
(GetSpawnables) names the topics after the robot's own name and the world 'default'.

A ROS name the bridge gives that ROS cannot take (a gz name such as /model/bot-1/cmd_vel, valid
for gz, is not valid for ROS) is named in an error and not served: the robot spawns, and its
other topics work. When the node's bridge changes, remake_topics() destroys the face's topics
and makes them again as the new bridge serves them; the plugin keeps running throughout.
"""

from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from service_tutorial.sim.plugins.gz_names import DEFAULT_WORLD_NAME
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.faces.face import PluginFace
from service_tutorial.world_node.gz_bridge import DEFAULT_ROS_TYPES, OTHER_ROS_TYPES
from service_tutorial.world_node.ros_names import check_topic
from service_tutorial.world_node.subscribers import SubscriberWatch
from service_tutorial.world_node.taken_at_tick import take_messages, TakenAtTick

# ros_gz_bridge's queue on both sides of a topic.
BRIDGE_DEPTH = 10


def gz_owner(world, model, plugin):
    """Return (world name, model name) a plugin's gz topics are named after."""
    world_name = world.name if world is not None else DEFAULT_WORLD_NAME
    model_name = model.name if model is not None else plugin.config.robot_name
    return world_name, model_name


def check_types(bridged, gz_type, model_name):
    """Refuse a BridgedTopic whose ROS type does not go with the gz type the system uses."""
    allowed = (DEFAULT_ROS_TYPES[gz_type],) + OTHER_ROS_TYPES.get(gz_type, ())
    if bridged.ros_type not in allowed:
        raise WorldError(f'topic {quoted(bridged.ros_name)} of model {quoted(model_name)} '
                         f'is bridged as {bridged.ros_type.__name__}, which does not go with '
                         f'{gz_type}: only {" or ".join(kind.__name__ for kind in allowed)} '
                         'does')


class GzFace(PluginFace):
    """A gz plugin's face: the ROS topics the bridge serves its gz topics as."""

    takes_commands = False  # True for a kind that takes commands (a drive, a controller)

    def __init__(self, node, world, model, plugin, namespace):
        """Ask the bridge how each gz topic is served; make_topics() makes them."""
        self.node = node
        self.world = world
        self.model = model
        self.plugin = plugin
        self.world_name, self.model_name = gz_owner(world, model, plugin)
        self._publishers = {}  # role -> (publisher, SubscriberWatch of it)
        self._subscriptions = []  # (subscription, callback) of the commands taken at tick
        self.served = self.serve()

    def gz_topics(self):
        """Return {role: (gz name, gz type, direction)} of the plugin's gz topics (each kind)."""
        raise NotImplementedError

    def serve(self):
        """Return {role: BridgedTopic, or None where the bridge serves none} of the gz topics."""
        bridge = self.node.gz_bridge
        served = {}
        for role, (gz_name, gz_type, direction) in self.gz_topics().items():
            bridged = None if gz_name is None else bridge.served(gz_name, gz_type, direction)
            if bridged is not None:
                try:
                    check_topic(self.node, self.model_name, bridged.ros_name)
                    check_types(bridged, gz_type, self.model_name)
                except WorldError as error:
                    if self.model is not None:  # not for a robot only described (spawnables)
                        self.node.get_logger().error(
                            f'{error}; gz topic {quoted(gz_name)} of {self.plugin.title} '
                            f'{quoted(self.plugin.block.name)} is not served')
                    bridged = None
            served[role] = bridged
        return served

    @property
    def topics(self):
        """Return the ROS names of the topics the face serves."""
        return tuple(bridged.ros_name for bridged in self.served.values() if bridged is not None)

    def make_topics(self):
        """Make the served topics on the node (each kind makes its own with these helpers)."""
        raise NotImplementedError

    def remake_topics(self):
        """Destroy the face's topics and make them again as the node's bridge serves them now."""
        self.destroy_topics()
        self.served = self.serve()
        self.make_topics()

    def publisher(self, role):
        """Make the ROS publisher of a role's topic, or return None if it is not served."""
        bridged = self.served.get(role)
        if bridged is None:
            return None
        publisher = self.create_publisher(bridged)
        self._publishers[role] = (publisher, SubscriberWatch(publisher))
        return publisher

    def listened(self, role):
        """Return the publisher of a role's topic if someone listens to it, else None."""
        publisher, watch = self._publishers.get(role, (None, None))
        return publisher if publisher is not None and watch.listened() else None

    def create_publisher(self, bridged):
        """Make a publisher of a BridgedTopic on the world node."""
        return self.node.create_publisher(
            bridged.ros_type, bridged.ros_name, BRIDGE_DEPTH,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))

    def subscription(self, role, callback):
        """Take the commands of a role's topic at each tick, handing each to callback."""
        bridged = self.served.get(role)
        if bridged is None:
            return
        subscription = self.node.create_subscription(
            bridged.ros_type, bridged.ros_name, callback, BRIDGE_DEPTH,
            callback_group=TakenAtTick(),
            event_callbacks=SubscriptionEventCallbacks(use_default_callbacks=False))
        self._subscriptions.append((subscription, callback))

    def take_commands(self):
        """Hand the commands that came since the last tick to their callbacks, in order."""
        for subscription, callback in self._subscriptions:
            for msg in take_messages(subscription):
                callback(msg)

    def warn_command(self, what, error):
        """Say that a command was ignored, and why, at most once a second."""
        self.node.get_logger().warning(f'ignored {what} for {self.model_name}: {error}',
                                       throttle_duration_sec=1.0)

    def destroy_topics(self):
        """Remove the face's topics from the node."""
        for publisher, _ in self._publishers.values():
            self.destroy_publisher(publisher)
        for subscription, _ in self._subscriptions:
            self.node.destroy_subscription(subscription)
        self._publishers, self._subscriptions = {}, []

    def destroy_publisher(self, publisher):
        """Remove one of the face's publishers from the node that made it."""
        self.node.destroy_publisher(publisher)

    def destroy(self):
        """Remove the face's topics from the node."""
        self.destroy_topics()
