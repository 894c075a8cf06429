"""
How a parameter_bridge process sets the world's bridge for as long as it runs.

The world is its own bridge (gz_bridge.py): a parameter_bridge process relays nothing. It
publishes its mappings once on BRIDGES_TOPIC, reliable and transient local so that a world
started after it hears them too, as YAML: {bridge: its node's full name, mappings: ros_gz_bridge's
entries with every name resolved}. The world sets them in its GzBridge under that name, and
drops them when no publisher of that node is left on BRIDGES_TOPIC (the process ended, however
it ended), so that the defaults come back. Bridges are told apart by their node's full name, as
ROS tells nodes apart (Jazzy's rclpy hands a subscription no publisher gid): two of one name
count as one, the later message in force. A publisher leaving is an event of the subscription
(matched); the graph then says which bridge left. Entries the world cannot serve are named in
one warning, and the others apply.
"""

from rclpy.clock import Clock, ClockType
from rclpy.event_handler import SubscriptionEventCallbacks
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from service_tutorial.world_node.bridge_config import BridgeConfigError, read_config_document
from service_tutorial.world_node.gz_bridge import bridged_topics
from std_msgs.msg import String
import yaml

# Absolute: a bridge in a robot's namespace still sets the world's bridge.
BRIDGES_TOPIC = '/service_tutorial/bridges'
# Each bridge's last message is kept for a world that comes later.
BRIDGES_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
# Wall time between two looks at the graph while it lags what the middleware said, in s.
GRAPH_LOOK_PERIOD = 0.2


def bridge_message(bridge, mappings):
    """Return the message that tells the world a bridge's mappings (YAML entries as dicts)."""
    return String(data=yaml.safe_dump({'bridge': bridge, 'mappings': mappings},
                                      sort_keys=False))


def full_name(namespace, name):
    """Return a node's full name, /namespace/name."""
    return namespace.rstrip('/') + '/' + name


class BridgeChannel:
    """The world's ear for parameter_bridge processes: it sets and drops their mappings."""

    def __init__(self, node):
        """Hear the bridges on node's graph and set their mappings in the node's GzBridge."""
        self.node = node
        self._seen = set()  # full names of the bridges the graph has listed
        self.bridges_sub = node.create_subscription(
            String, BRIDGES_TOPIC, self.bridges_callback, BRIDGES_QOS,
            event_callbacks=SubscriptionEventCallbacks(matched=self.matched_callback))
        # Runs only while the graph and the middleware disagree; on the steady wall clock, since
        # simulation time stands still in a paused world (or one with use_sim_time).
        self.graph_timer = node.create_timer(GRAPH_LOOK_PERIOD, self.graph_callback,
                                             clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.graph_timer.cancel()

    @property
    def bridge(self):
        """Return the GzBridge the node serves its gz topics by (node.gz_bridge)."""
        return self.node.gz_bridge

    def bridges_callback(self, msg):
        """Set the mappings a bridge published, in place of its earlier ones."""
        logger = self.node.get_logger()
        try:
            document = yaml.safe_load(msg.data)
            bridge = document['bridge']
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
        self.graph_callback()  # it may have left already

    def matched_callback(self, info):
        """Look for the bridges that left when a publisher of BRIDGES_TOPIC goes."""
        if info.current_count_change < 0 and self.bridge.owners:
            self.graph_callback()

    def graph_callback(self):
        """Drop the mappings of every bridge that has no publisher on BRIDGES_TOPIC left."""
        present = {full_name(info.node_namespace, info.node_name)
                   for info in self.node.get_publishers_info_by_topic(BRIDGES_TOPIC)}
        self._seen |= present
        # The middleware's count is exact, the graph may lag it either way: a bridge the graph
        # never listed is gone once the graph lists every publisher the middleware knows.
        matched = self.bridges_sub.get_publisher_count()
        for bridge in self.bridge.owners:
            if bridge not in present and (bridge in self._seen or matched <= len(present)):
                self._seen.discard(bridge)
                self.bridge.drop(bridge)
                self.node.get_logger().info(f'bridge {bridge} left: its mappings are dropped')
        if not set(self.bridge.owners) <= present or len(present) > matched:
            self.graph_timer.reset()  # look again until the graph agrees
        else:
            self.graph_timer.cancel()

    def destroy(self):
        """Stop hearing bridges."""
        self.node.destroy_timer(self.graph_timer)
        self.node.destroy_subscription(self.bridges_sub)
