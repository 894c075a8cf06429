"""
How a parameter_bridge process sets the world's bridge for as long as it runs.

The world is its own bridge (gz_bridge.py): a parameter_bridge process relays nothing. It
publishes its mappings once on BRIDGES_TOPIC, reliable and transient local so that a world
started after it hears them too, as YAML: {bridge: its node's full name, presence: a token of
its own, mappings: ros_gz_bridge's entries with every name resolved}. Before that it makes a
publisher on its presence topic (presence_topic(token), hidden, never published on). The world
sets the mappings in its GzBridge under the bridge's name and subscribes to the presence topic:
the middleware counts that one publisher exactly and says when it goes (the process ended,
however it ended), and then the world drops the mappings, so that the defaults come back. A
bridge's name may come back in another process while the graph still lists the one before, so
the graph's names do not tell bridges apart; the tokens do. Bridges of one full name count as
one, as ROS counts nodes: the later message is in force, and only its process's leaving drops
the mappings. Entries the world cannot serve are named in one warning, and the others apply.
"""

import re
import uuid

from rclpy.clock import Clock, ClockType
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from service_tutorial.world_node.bridge_config import BridgeConfigError, read_config_document
from service_tutorial.world_node.gz_bridge import bridged_topics
from std_msgs.msg import Empty, String
import yaml

# Absolute: a bridge in a robot's namespace still sets the world's bridge.
BRIDGES_TOPIC = '/service_tutorial/bridges'
# Each bridge's last message is kept for a world that comes later.
BRIDGES_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
# A hidden topic per bridge process ('_' hides it from `ros2 topic list`), and its token.
PRESENCE_PREFIX = '/_service_tutorial/bridge_'
PRESENCE_TOKEN = re.compile(r'[0-9a-f]{32}')
PRESENCE_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE)
# Wall time between two looks at the graph while a bridge's presence is listed there but not
# yet matched, in s.
GRAPH_LOOK_PERIOD = 0.2


def presence_topic(token):
    """Return the hidden topic that a bridge's process holds a publisher on while it runs."""
    return PRESENCE_PREFIX + token


def bridge_message(bridge, token, mappings):
    """Return the message that tells the world a bridge's mappings (YAML entries as dicts)."""
    return String(data=yaml.safe_dump({'bridge': bridge, 'presence': token,
                                       'mappings': mappings}, sort_keys=False))


def full_name(namespace, name):
    """Return a node's full name, /namespace/name."""
    return namespace.rstrip('/') + '/' + name


class BridgeAnnouncement:
    """A bridge's side of the channel: its mappings apply in the world while this lives."""

    def __init__(self, node, mappings):
        """Tell the world the mappings of node, a bridge (YAML entries as dicts)."""
        self.node = node
        token = uuid.uuid4().hex
        self.presence_pub = node.create_publisher(Empty, presence_topic(token), PRESENCE_QOS)
        self.bridges_pub = node.create_publisher(String, BRIDGES_TOPIC, BRIDGES_QOS)
        self.bridges_pub.publish(bridge_message(node.get_fully_qualified_name(), token,
                                                mappings))

    def destroy(self):
        """Withdraw the mappings: the world drops them when it sees the presence go."""
        self.node.destroy_publisher(self.bridges_pub)
        self.node.destroy_publisher(self.presence_pub)


class Presence:
    """The world's subscription to one bridge process's presence topic."""

    def __init__(self, token, subscription):
        """Hold a bridge's token and the subscription that counts its process."""
        self.token = token
        self.subscription = subscription
        self.matched = False  # the middleware has matched its publisher once


class BridgeChannel:
    """The world's ear for parameter_bridge processes: it sets and drops their mappings."""

    def __init__(self, node):
        """Hear the bridges on node's graph and set their mappings in the node's GzBridge."""
        self.node = node
        self._presences = {}  # bridge full name -> Presence of the process in force
        # Without rclpy's default handlers of incompatible QoS: two more waitables in the turn
        # of the world's executor at every tick.
        self.bridges_sub = node.create_subscription(
            String, BRIDGES_TOPIC, self.bridges_callback, BRIDGES_QOS,
            event_callbacks=SubscriptionEventCallbacks(use_default_callbacks=False))
        # Runs only while a presence is listed on the graph but not matched yet; on the steady
        # wall clock, since simulation time stands still in a paused world (or one with
        # use_sim_time).
        self.graph_timer = node.create_timer(GRAPH_LOOK_PERIOD, self.graph_callback,
                                             clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.graph_timer.cancel()

    @property
    def bridge(self):
        """Return the GzBridge the node serves its gz topics by (node.gz_bridge)."""
        return self.node.gz_bridge

    def bridges_callback(self, msg):
        """Set the mappings a bridge published, in place of its name's earlier ones."""
        logger = self.node.get_logger()
        try:
            document = yaml.safe_load(msg.data)
            bridge, token = document['bridge'], document['presence']
            if not isinstance(bridge, str) or not PRESENCE_TOKEN.fullmatch(str(token)):
                raise KeyError('bridge or presence')
            reading = read_config_document(document['mappings'], source=f'of bridge {bridge}')
        except (yaml.YAMLError, TypeError, KeyError, BridgeConfigError) as error:
            logger.error(f"a message on {BRIDGES_TOPIC} is not a bridge's mappings ({error}); "
                         'it is ignored')
            return
        for error in reading.errors:
            logger.error(error)
        topics, unserved = bridged_topics(reading.entries)
        if unserved:
            logger.warning(f'bridge {bridge}: {len(unserved)} of its mappings name types this '
                           f'world does not serve, left out: {"; ".join(unserved)}')
        self.bridge.set_mappings(bridge, topics)
        logger.info(f'bridge {bridge}: {len(topics)} mapping(s) applied')
        self.watch(bridge, token)

    def watch(self, bridge, token):
        """Count the process of a bridge's token from now on, in place of its name's earlier."""
        earlier = self._presences.get(bridge)
        if earlier is not None and earlier.token == token:
            return
        self._forget(bridge)
        presence = Presence(token, None)
        presence.subscription = self.node.create_subscription(
            Empty, presence_topic(token), lambda msg: None, PRESENCE_QOS,
            event_callbacks=SubscriptionEventCallbacks(
                matched=lambda info: self.matched_callback(bridge, presence, info)))
        self._presences[bridge] = presence
        self.look(bridge, presence)

    def matched_callback(self, bridge, presence, info):
        """Drop a bridge's mappings when its process's presence goes."""
        if self._presences.get(bridge) is not presence:
            return  # a process its name no longer stands for
        if info.current_count > 0:
            presence.matched = True
        elif presence.matched:
            self.leave(bridge)

    def look(self, bridge, presence):
        """
        Judge a presence the middleware has not matched (yet); return whether it may come.

        A process's presence publisher is announced before its mappings, so the graph lists it
        by the time the mappings arrive: not listed and not matched, the process has ended.
        """
        if presence.matched or presence.subscription.get_publisher_count() > 0:
            presence.matched = True
            return False
        if self.node.count_publishers(presence_topic(presence.token)) > 0:
            self.graph_timer.reset()  # listed: the match is on its way
            return True
        self.leave(bridge)
        return False

    def graph_callback(self):
        """Look again at the presences listed on the graph but not matched."""
        pending = [self.look(bridge, presence)
                   for bridge, presence in list(self._presences.items()) if not presence.matched]
        if not any(pending):
            self.graph_timer.cancel()

    def leave(self, bridge):
        """Drop the mappings of a bridge whose process has ended."""
        self._forget(bridge)
        self.bridge.drop(bridge)
        self.node.get_logger().info(f'bridge {bridge} left: its mappings are dropped')

    def _forget(self, bridge):
        presence = self._presences.pop(bridge, None)
        if presence is not None:
            self.node.destroy_subscription(presence.subscription)

    def destroy(self):
        """Stop hearing bridges."""
        for bridge in list(self._presences):
            self._forget(bridge)
        self.node.destroy_timer(self.graph_timer)
        self.node.destroy_subscription(self.bridges_sub)
