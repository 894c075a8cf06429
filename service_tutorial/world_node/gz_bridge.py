"""
How the world serves gz topics on ROS: ros_gz_bridge's mapping, in one place.

gz-sim's systems and sensors know their gz topics (sim/plugins/gz_names.py), as gz-sim's do;
ros_gz_bridge decides what ROS sees of each: its ROS name, its ROS type, and the direction it
crosses in. The world is its own bridge, with no relay and no copy: the faces of the gz
plugins (faces/gz_*.py) ask GzBridge.served() for each of their gz topics and make that ROS
topic, or none. With no bridge set up, every gz topic is served under its own name (gz's
names are absolute) with the bridge's default ROS type for its gz type (DEFAULT_ROS_TYPES,
ros_gz_bridge's mappings: Twist for a command), in the direction its system uses it. A bridge
configuration (ros_gz_bridge's YAML, parameter_bridge's arguments, read by bridge_config.py) is
a set of BridgedTopics that take the place of the defaults for the gz topics they name: another
ROS name, TwistStamped for Twist, one direction only. Each bridge running (a parameter_bridge
process: bridge_channel.py) sets its own set and it is dropped when the bridge leaves; where two
bridges name the same gz topic, the later one counts. Whoever makes the topics hears of every
change (on_change) and makes them again.
"""

from dataclasses import dataclass

from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, Imu, JointState, LaserScan, NavSatFix
from sensor_msgs.msg import PointCloud2
from service_tutorial.world_node.bridge_config import BIDIRECTIONAL, DEFAULT_QUEUE
# The directions, for the faces: they name them from here.
from service_tutorial.world_node.bridge_config import GZ_TO_ROS, ROS_TO_GZ  # noqa: F401
from std_msgs.msg import Bool, Float64
from tf2_msgs.msg import TFMessage

# gz message type -> the ROS type ros_gz_bridge pairs it with when a mapping names none other.
DEFAULT_ROS_TYPES = {
    'gz.msgs.Twist': Twist,
    'gz.msgs.Odometry': Odometry,
    'gz.msgs.OdometryWithCovariance': Odometry,
    'gz.msgs.Pose_V': TFMessage,
    'gz.msgs.Model': JointState,
    'gz.msgs.Double': Float64,
    'gz.msgs.Boolean': Bool,
    'gz.msgs.LaserScan': LaserScan,
    'gz.msgs.PointCloudPacked': PointCloud2,
    'gz.msgs.Image': Image,
    'gz.msgs.CameraInfo': CameraInfo,
    'gz.msgs.IMU': Imu,
    'gz.msgs.NavSat': NavSatFix,
}
# The other ROS types a mapping may pair a gz type with (ros_gz_bridge's factories).
OTHER_ROS_TYPES = {'gz.msgs.Twist': (TwistStamped,)}


def ros_type_name(ros_type):
    """Return a ROS message class's type name, pkg/msg/Name."""
    return f'{ros_type.__module__.split(".")[0]}/msg/{ros_type.__name__}'


# ROS type name -> class, of every ROS type the world serves a gz topic as.
SERVED_ROS_TYPES = {ros_type_name(ros_type): ros_type for ros_type in (
    *DEFAULT_ROS_TYPES.values(),
    *(other for types in OTHER_ROS_TYPES.values() for other in types))}


@dataclass(frozen=True)
class BridgedTopic:
    """One gz topic as ROS sees it: its ROS name and type, and which way it crosses."""

    gz_name: str
    gz_type: str  # gz.msgs.Twist...
    ros_name: str
    ros_type: type  # the ROS message class, geometry_msgs.msg.Twist...
    direction: str  # GZ_TO_ROS, ROS_TO_GZ or BIDIRECTIONAL
    publisher_queue: int = DEFAULT_QUEUE  # of the ROS publisher (gz to ROS)
    subscriber_queue: int = DEFAULT_QUEUE  # of the ROS subscription (ROS to gz)

    def carries(self, direction):
        """Tell whether the topic crosses the bridge in a direction (GZ_TO_ROS, ROS_TO_GZ)."""
        return self.direction in (direction, BIDIRECTIONAL)


class GzBridge:
    """The world's bridge: which gz topics ROS sees, under which names and types."""

    def __init__(self, mappings=()):
        """Serve every gz topic by default, or as one of the BridgedTopics in mappings says."""
        self._owners = {}  # owner -> {gz name: BridgedTopic}, in the order they were set
        self._mappings = {}  # gz name -> BridgedTopic, of every owner
        self._listeners = []
        if mappings:
            self.set_mappings(None, mappings)

    def on_change(self, callback):
        """Call callback() after every change of the mappings, once per change."""
        self._listeners.append(callback)

    def set_mappings(self, owner, mappings):
        """Serve the gz topics of BridgedTopics as they say, in place of owner's earlier ones."""
        self._owners.pop(owner, None)
        self._owners[owner] = {mapping.gz_name: mapping for mapping in mappings}
        self._changed()

    def drop(self, owner):
        """Serve again as before the gz topics owner's mappings named; False if it had none."""
        if self._owners.pop(owner, None) is None:
            return False
        self._changed()
        return True

    @property
    def owners(self):
        """Return the owners whose mappings apply, in the order they were set."""
        return tuple(self._owners)

    def _changed(self):
        self._mappings = {gz_name: mapping for mappings in self._owners.values()
                          for gz_name, mapping in mappings.items()}
        for callback in self._listeners:
            callback()

    def served(self, gz_name, gz_type, direction):
        """
        Return the BridgedTopic a system's gz topic is served as, or None if it is not.

        direction: which way the system needs it: GZ_TO_ROS for what it publishes, ROS_TO_GZ
        for the commands it takes. A mapping of the topic that does not carry it that way, or
        names another gz type than the system's, leaves it unserved, as such a bridge would
        carry nothing in gz.
        """
        mapping = self._mappings.get(gz_name)
        if mapping is None:
            return BridgedTopic(gz_name, gz_type, gz_name, DEFAULT_ROS_TYPES[gz_type],
                                direction)
        return mapping if mapping.carries(direction) and mapping.gz_type == gz_type else None


def bridged_topics(entries, *, resolve=lambda name: name):
    """
    Return (BridgedTopics, unserved) of bridge_config.BridgeEntries.

    unserved: the entries of pairs ros_gz_bridge has and this world does not serve (a Clock,
    a String), as one line each; resolve: turns an entry's ROS name into the full name, as the
    bridge's node resolves it.
    """
    topics, unserved = [], []
    for entry in entries:
        ros_type = SERVED_ROS_TYPES.get(entry.ros_type)
        default = DEFAULT_ROS_TYPES.get(entry.gz_type)
        if default is None or ros_type not in (default, *OTHER_ROS_TYPES.get(entry.gz_type, ())):
            unserved.append(f'{entry.gz_name} ({entry.ros_type} / {entry.gz_type})')
            continue
        topics.append(BridgedTopic(entry.gz_name, entry.gz_type, resolve(entry.ros_name),
                                   ros_type, entry.direction, entry.publisher_queue,
                                   entry.subscriber_queue))
    return topics, unserved


def twist_of(msg):
    """Return the geometry_msgs/Twist of a Twist or TwistStamped command."""
    return msg.twist if isinstance(msg, TwistStamped) else msg
